#pragma once
// A model file as `epa identify` wrote it from open-loop runs of the default physics plant
// (epa excite --plant physics --seed 1,2,3 --duration 30; epa identify ex1 ex2 --validate ex3):
// test input for what the law and the stick-slip model do on that plant, shared so that the tests
// read one model, not two copies of it.
namespace epa::testing {

inline constexpr const char* kPhysicsIdentifiedModelToml = R"(schema = "epa-model/1"
Ts = 0.005
mm_per_volt = 50.0
source = 'epa identify: na=4 nb=1 nk=1 from ex1.csv, ex2.csv; validation free-run fit 54.86 %; stick-slip model: validation free-run fit 96.70 %'
axis_model = "stick-slip"

[arx]
A = [1.0, -1.089166190990138, -0.32295729667453776, 0.1172131221902894, 0.29491036547438637]
B = [0.0, 0.0024317052709731135]

[dead_zone]
m_r = 1.2198620103542206
m_l = 1.0707
b_r = 1.345
b_l = -1.8193712892465246

[stick_slip]
break_right_v = 1.176969689128404
break_left_v = -1.683703334845168
speed_right_mm_s_per_v = 112.57081259160479
speed_left_mm_s_per_v = 109.02932094462616
spring_rad_s = 59.015440817565505
damping_ratio = 0.20904450655623621
coulomb_mm = 5.66702578402857
static_mm = 5.768196811811399
spool_lag_s = 0.013662491569187415
delay_samples = 1
)";

}  // namespace epa::testing
