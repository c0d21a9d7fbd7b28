// Bodies' quaternions as ODE stores them (used by cpp/dynamics): ODE normalises a quaternion
// whenever it is set (dBodySetQuaternion: dxSafeNormalize4, then the rotation matrix from it), so
// a restored state is only bit-identical if the stored quaternion is a fixed point of that
// normalisation (it need not be: normalisation can alternate between two neighbours).
#pragma once

#include <ode/ode.h>

namespace ernest::solver {

/// Moves body b's quaternion to a nearby fixed point of ODE's normalisation: its largest
/// component nudged by a few ulps (a 1e-16 change) until setting it returns it unchanged; the
/// rotation matrix is then recomputed from exactly that quaternion. Called after every step.
void canonicalise_quaternion(dBodyID b);

/// The quaternion canonicalise_quaternion() would leave after dBodySetQuaternion(b, q), for an
/// unnormalised q, without calling ODE (ODE's normalisation, then the same nudges): setting `out`
/// then normalises it to itself, one call into ODE instead of two or more per body and step.
/// False (out unspecified) where this cannot be answered without ODE: the quick fixed-point test
/// did not agree with this ODE build at start-up, q is zero or not finite, or no fixed point
/// lies within the nudges (never seen).
bool fixed_point_quaternion(const dReal* q, dReal out[4]);

}  // namespace ernest::solver
