#pragma once
// Physical parameters of the pneumatic plant (PneumaticPlant) and their file format,
// `epa-pneumatic/1` (TOML; config/pneumatic-plant.toml holds the defaults with a comment each):
//
//   schema = "epa-pneumatic/1"
//   [supply]    supply_pressure_bar, atmospheric_pressure_bar, temperature_k
//   [cylinder]  bore_mm, rod_mm, stroke_mm, dead_volume_a_cm3, dead_volume_b_cm3, piston_mass_kg,
//               polytropic_index, leak_a_mm2, leak_b_mm2
//   [friction]  static_friction_n, coulomb_friction_n, stribeck_velocity_mps, viscous_friction_n_per_mps,
//               lugre_stiffness_n_per_m, lugre_damping_n_s_per_m
//   [valve]     orifice_area_mm2, discharge_coefficient, spool_time_constant_s, overlap_pos_v, overlap_neg_v
//
// A key left out keeps its default; an unknown key is refused with its name and line.
// The defaults are sized like the paper's rig (FESTO cylinder, 500 mm stroke, 6 bar supply,
// Enfield 5/3 proportional valve): about 0.9 m/s at full command, and a valve-command dead zone
// of [-1.7, +1.2] V like the paper's identified b_l = -1.722 V, b_r = +1.232 V.
#include <string>
#include <string_view>

#include "core/result.hpp"

namespace epa::plant {

struct PneumaticParams {
  // [supply]
  double supply_pressure_bar = 6.0;          // gauge, at the valve's P port (paper: "6 kPa", read as 6 bar)
  double atmospheric_pressure_bar = 1.01325; // absolute; the exhaust and the rod's outer face
  double temperature_k = 293.15;            // supply air; chambers taken at the same temperature

  // [cylinder] chamber A is the cap side (pressure pushes towards +x), B the rod side
  double bore_mm = 32.0;            // piston diameter (FESTO DNC-32)
  double rod_mm = 12.0;             // rod diameter: chamber B's area is the annulus
  double stroke_mm = 500.0;         // end stops at 0 and stroke_mm
  double dead_volume_a_cm3 = 10.0;  // chamber A at x = 0, with the valve port and tubing
  double dead_volume_b_cm3 = 10.0;  // chamber B at x = stroke
  double piston_mass_kg = 1.5;      // piston, rod and carriage
  double polytropic_index = 1.4;    // n in dp/dt = n(RT m' - p V')/V; 1.4: adiabatic, 1.0: isothermal
  double leak_a_mm2 = 0.0;          // effective area of a leak from chamber A to atmosphere (a worn seal); 0: tight
  double leak_b_mm2 = 0.0;          // the same for chamber B

  // [friction] F(v) = sgn(v) [Fc + (Fs - Fc) exp(-(v/vs)^2)] + b v, sticking below Fs at v = 0
  double static_friction_n = 40.0;           // Fs, breakaway force
  double coulomb_friction_n = 25.0;          // Fc, sliding force at speed (<= Fs)
  double stribeck_velocity_mps = 0.02;       // vs, how fast friction falls from Fs to Fc
  double viscous_friction_n_per_mps = 40.0;  // b
  // LuGre bristles instead of the stick test when > 0: dz/dt = v - sigma0 |v| z / g(v), friction
  // sigma0 z + sigma1 dz/dt + b v, g(v) the Stribeck curve above (Canudas de Wit et al. 1995).
  // The piston never sticks hard: below breakaway it creeps a presliding distance of about F / sigma0.
  double lugre_stiffness_n_per_m = 0.0;    // sigma0; 0: the stick test (the default)
  double lugre_damping_n_s_per_m = 0.0;    // sigma1

  // [valve] 5/3 closed-centre proportional valve, spool position in command volts (-10..10)
  double orifice_area_mm2 = 4.0;         // each metering edge's area at full opening (+-10 V)
  double discharge_coefficient = 0.8;    // Cd: effective area = Cd * geometric area
  double spool_time_constant_s = 0.005;  // first-order lag from command to spool position
  double overlap_pos_v = 1.2;   // spool overlap: P->A, B->T start to open above this command
  double overlap_neg_v = -1.7;  // P->B, A->T start to open below this command

  // Every field finite and in its physical range, rod < bore, Fc <= Fs, overlaps inside +-10 V.
  // The message names the field (as "[table] key") and the value.
  core::Status validate() const;

  bool operator==(const PneumaticParams&) const = default;
};

// Errors name the source (file name) and the line, and the key that is unknown, mistyped or out
// of range; the result is validated.
core::Result<PneumaticParams> parse_pneumatic_toml(const std::string& text, const std::string& source_name);
core::Result<PneumaticParams> read_pneumatic_file(const std::string& path);
std::string format_pneumatic_toml(const PneumaticParams& params);  // reads back to the same values
// Sets one key of the file, named bare ("supply_pressure_bar") or with its table
// ("supply.supply_pressure_bar"), and validates the result. On an error (an unknown key, listing
// the known ones; a value out of range, as validate() names it) `params` is left as it was.
core::Status set_pneumatic_key(PneumaticParams& params, std::string_view key, double value);
core::Status write_pneumatic_file(const std::string& path, const PneumaticParams& params);

}  // namespace epa::plant
