// Bekker–Wong soil parameters (seed 004, Table 2) with the DARTS regularisation constants.
#pragma once

#include <string>
#include <vector>

namespace ernest::soil {

/// Parameters of the Bekker–Wong model of seed 004 §3.3. Units are SI (Pa, m, rad), so Table 2's
/// kN values are multiplied by 1e3. The defaults are the M90 Mars simulant used for training.
struct SoilParameters {
  double density = 1520.0;                 ///< rho [kg/m^3]; unit weight rho*g enters eq 24
  double cohesion = 2000.0;                ///< c [Pa]
  double friction_angle = 0.6108652382;    ///< phi [rad] (35 deg)
  double sinkage_exponent = 1.3;           ///< n [-]
  double k_c = 572.1e3;                    ///< cohesion modulus [N/m^(n+1)]
  double k_phi = 4915.3e3;                 ///< friction modulus [N/m^(n+2)]
  double shear_modulus_x = 0.0254;         ///< K_x [m] (Table 2 gives one K for x and y)
  double shear_modulus_y = 0.0254;         ///< K_y [m]
  double a0 = 0.43, a1 = 0.32;             ///< theta_m coefficients, eq 14
  double b0 = -0.16, b1 = 0.0;             ///< theta_r coefficients, eq 15
  double eps_slip = 100.0;                 ///< slip regularisation [(m/s)^-2], eq 12
  double eps_motion = 5e-5;                ///< rest threshold [m/s], eq 16
  double eps_contact_x = 0.01;             ///< contact-velocity threshold [m/s], eq 28
  double eps_contact_y = 0.01;             ///< contact-velocity threshold [m/s], eq 29
  /// Ours, not the paper's: sign(v_x) in eqs 30 and 32 is replaced by clamp(v_x/eps, -1, 1) so
  /// forces stay continuous when v_x crosses zero while the wheel spins. 0 gives the paper's sign.
  double eps_direction = 0.01;
  /// Ours, not the paper's: in eq 12's braking branch the ratio -v_cx / v_x is clamped to
  /// [-1, 0] before the regularisation factor (1 - exp(-eps_slip v_x^2)) multiplies it, as the
  /// driving branch's ratio v_cx / (v_cx - v_x) already is by its form. Then both branches go to
  /// 0 on the same velocity scale eps_slip^-1/2, as §3.3 says the factor is for. Printed (false:
  /// clamped after), a wheel spinning at |v_cx| while its centre drifts back has
  /// s ~ -eps_slip |v_cx| |v_x|: at ERNEST's 0.2 m/s and eps_slip 1e4, s reaches -1 within
  /// 0.5 mm/s of v_x and the soil force jumps by ~150 N, a law too steep for the simulator's
  /// step to resolve (benchmarks/RESULTS.md, "step independence"). Identical whenever
  /// |v_cx| <= |v_x| or |v_x| >> eps_slip^-1/2.
  bool slip_clamp_first = true;
  double gravity = 9.81;                   ///< [m/s^2], turns rho into unit weight in eq 24

  /// Throws std::invalid_argument naming the first field outside its allowed range.
  void validate() const;

  /// Table 2 "Dry sand" (Jia et al. tuned to ERNEST's drawbar-pull experiment).
  static SoilParameters dry_sand();
  /// Table 2 "M90 Mars simulant" (Oravec et al.), the training soil.
  static SoilParameters m90();
  /// Ours (assumption, not from the papers): damp sand with apparent cohesion from capillary
  /// suction, lower friction angle and a softer pressure–sinkage law than M90. See the .cpp.
  static SoilParameters wet_sand();
  /// Preset by name: "dry_sand", "m90" or "wet_sand"; std::invalid_argument otherwise.
  static SoilParameters preset(const std::string& name);
  static std::vector<std::string> preset_names();
};

}  // namespace ernest::soil
