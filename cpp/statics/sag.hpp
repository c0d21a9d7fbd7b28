// Compliance (sag) model of seed 003 §5.1.1, eqs 1–12: a rigid robot standing on contacts that
// are each three orthogonal linear springs (Fig. 9, eq 3), with unilateral contact and a lift
// Δh per foot (eqs 9–12) so that a foot being lifted unloads gradually. Robot-agnostic: the
// inputs are the unsagged foot positions, CG, mass, gravity and spring constants; any rigid-body
// points (leg attachment points, measurement points) are carried along to their sagged pose.
//
// Formulation (see sag.cpp for the equations): the unknowns are the N foot displacements Δr_i and
// the final CG r_f,CG (3N + 3). The paper names the forces as unknowns; by eqs 10–12 each force is
// a function of its foot's displacement, which is one-to-one for a loaded foot (eq 3) but not for
// a foot in the air (zero force at any height), so we take the displacements as the unknowns: the
// same system, defined for every combination of feet in the air. The residuals are eqs 4–5
// (equilibrium), 6–7 (distances between successive and alternate feet) and 8 (CG to each foot),
// over-constrained as the paper describes, solved by Eigen's LevenbergMarquardt with the set of
// loaded feet held fixed (smooth residuals), inside an active-set loop that moves feet in or out
// of contact until eqs 10–12's "if in contact" holds for every foot. If that loop fails (a foot
// that must unload leaves feet that cannot hold the robot, which then leans onto a lifted foot),
// it is retried along the quasi-static path of lifting: the lifts grow from zero in steps, each
// solved from the last. The chassis
// rotation is then backtracked (the paper's last step) as the rigid transform that best maps the
// unsagged feet and CG onto the sagged ones (Eigen::umeyama). The vertical rigidity of the feet
// comes from eq 8, so the CG must not lie in the plane of the feet.
#pragma once

#include <Eigen/Core>

namespace ernest::statics {

/// One stance of the sag model. Vectors are in a fixed world frame [m], forces [N].
struct SagProblem {
  Eigen::Matrix3Xd feet;       ///< r_0,i: unsagged foot (fork) positions, eq 1 (N < 3: Unstable)
  Eigen::Matrix3Xd stiffness;  ///< k_xx, k_yy, k_zz of each foot [N/m] (> 0), eq 3
  /// Δh_i, eq 9: how far foot i is above the point where it starts bearing load, along the
  /// spring frame's z axis (> 0 lifted, < 0 pre-compressed). Empty = all zeros. +inf marks a
  /// foot in the air that never touches (it still moves with the rigid body). NaN is rejected.
  Eigen::VectorXd lift;
  Eigen::Vector3d cg = Eigen::Vector3d::Zero();  ///< r_0,CG, eq 1
  double mass = 1.0;                             ///< [kg] (> 0)
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};      ///< [m/s^2], non-zero
  /// Columns: the directions of the x, y and z (normal, pointing out of the ground) springs
  /// (Fig. 9's tangential–normal frame); the world axes by default. Must be a rotation.
  Eigen::Matrix3d spring_frame = Eigen::Matrix3d::Identity();
  Eigen::Vector3d chassis_position = Eigen::Vector3d::Zero();     ///< unsagged chassis origin
  Eigen::Matrix3d chassis_rotation = Eigen::Matrix3d::Identity();  ///< unsagged orientation
  Eigen::Matrix3Xd body_points;  ///< rigid-body points to report sagged (e.g. leg attachments)

  /// Throws std::invalid_argument naming the field (shape, finiteness, k > 0, mass > 0, ...).
  void validate() const;
};

struct SagOptions {
  int max_evaluations = 400;        ///< residual evaluations allowed to LM (>= 10)
  double tolerance = 1e-14;         ///< LM's relative ftol and xtol, (0, 1e-3]
  /// Largest accepted equilibrium residual (eqs 4–5 over m|g|) for status Converged, (0, 1].
  double equilibrium_tolerance = 1e-7;
  /// Penetration [m] accepted for an unloaded foot, [0, 1]. Eqs 10–11 switch a foot's full
  /// tangential springs on at touchdown (their rest point is the unsagged foot), so the
  /// tangential forces jump there, and in a band of Δh of order θ·|Δr_xy| (a micrometre for
  /// ATHLETE-like stances) no contact set satisfies eqs 10–12 exactly: loaded, the foot would
  /// pull; unloaded, it dips into the ground. There the foot is reported unloaded.
  double contact_tolerance = 1e-6;
  void validate() const;
};

enum class SagStatus {
  Converged,     ///< equilibrium found and at least three feet loaded
  Unstable,      ///< no static equilibrium: fewer than three feet can be loaded, the CG
                 ///< projects outside their support polygon, or a foot that must unload
                 ///< leaves feet that cannot hold the robot (it tips on its compliant contacts,
                 ///< e.g. a high CG near an edge)
  NotConverged,  ///< LM stopped without reaching equilibrium although the stance looks stable
};

const char* to_string(SagStatus status);

struct SagResult {
  SagStatus status = SagStatus::NotConverged;
  Eigen::Matrix3Xd forces;       ///< f_i: reaction of the ground on foot i [N], eqs 10–12
  Eigen::Matrix3Xd deflections;  ///< Δr_i: displacement of foot i, eq 2 [m] (spring deflection
                                 ///< when loaded, eq 3; the rigid motion of a foot in the air)
  Eigen::VectorXd compression;   ///< -(Δr_i.z_spring + Δh_i): > 0 loaded, <= 0 in the air [m]
                                 ///< (-inf for a foot with lift +inf)
  Eigen::Vector3d cg = Eigen::Vector3d::Zero();  ///< r_f,CG
  /// Rigid transform unsagged -> sagged (x' = rotation x + translation), eq 2 backtracked.
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Vector3d chassis_position = Eigen::Vector3d::Zero();     ///< sagged chassis origin
  Eigen::Matrix3d chassis_rotation = Eigen::Matrix3d::Identity();  ///< sagged orientation
  Eigen::Matrix3Xd body_points;  ///< sagged body points
  int loaded = 0;                ///< feet bearing load
  double equilibrium_residual = 0.0;  ///< |eq 4|/(m|g|) + |eq 5|/(m|g|L)
  double rigidity_residual = 0.0;     ///< largest distance of a foot/CG from the rigid fit [m]
  int evaluations = 0;                ///< residual evaluations used by LM
};

/// Solves one stance. Throws std::invalid_argument (naming the field) for invalid input; every
/// valid input gets a defined result (status Unstable for < 3 feet, forces zero and pose
/// unchanged). Allocates its small LM workspace (about 25 x 21 doubles for six feet).
SagResult solve_sag(const SagProblem& problem, const SagOptions& options = {});

}  // namespace ernest::statics
