// Interoperability, the whole integration with the npm package modbus-serial (its promise API over
// TCP), as a Node.js HMI/SCADA integration would drive the appliance.
//
//   node flow_test.js <epa binary> <source dir> <host> <port>
//
// The appliance is already running on host:port (tests/interop/modbus_serial_test.sh starts it with
// [limits] soft_max_mm = 300 and heartbeat_timeout_s = 5, and stops it by its PID). Steps, in order:
// the register map from `epa registers --csv` (every address used is looked up there by name, floats
// must be ABCD), FC43/14 (MajorMinorRevision = `epa --version`), enable (mode RUN), unlock + record 1
// in one FC16, the start/ack handshake to in_position + target_reached, halt of record 2 mid-way,
// jog in MANUAL (control word held with a keep-alive, then the jog_minus coil with the client silent:
// it brakes by itself), a soft-limit fault reset by the control word's reset bit, and the fault
// history (count + newest entry). A heartbeat runs on a second connection all along.
// Floats: readHoldingRegisters/readInputRegisters' `buffer` is the registers' bytes as sent (high
// word first), so Buffer.readFloatBE(0) decodes ABCD; writes use Buffer.writeFloatBE and two words.
// Exit 0 when every step passes; 1 with "FAIL: <step>: <what>" otherwise. Every wait is bounded.
"use strict";

const { execFileSync } = require("child_process");
const path = require("path");
const ModbusRTU = require("modbus-serial");

const [epa, src, host, portText] = process.argv.slice(2);
if (!epa || !src || !host || !portText) {
  console.error("usage: node flow_test.js <epa binary> <source dir> <host> <port>");
  process.exit(2);
}
const port = Number(portText);
const UNIT = 1;
const UNLOCK_KEY = "5e3a9c17d24b086f"; // [modbus] unlock_key of the test appliances (tests/support/appliance.sh)
const SOFT_MAX_MM = 300;
const JOG_SPEED_MM_S = 20;  // [motion] jog_speed_mm_s default
const JOG_KEEPALIVE_S = 1;  // [motion] jog_keepalive_s default
const BIT_NAMES = ["ready", "run_enabled", "moving", "in_position", "target_reached", "following_error",
  "warning", "fault_latched", "ack", "halted", "jogging", "manual_mode", "off_target"];
const S = Object.fromEntries(BIT_NAMES.map((n, i) => [n, 1 << i])); // status_word bits
const CW = { start: 1, halt: 2, jog_plus: 4, jog_minus: 8, reset: 16 };  // control_word bits

let step = "setup";
let passed = 0;
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const now = () => Number(process.hrtime.bigint() / 1000000n);
const bits = (w) => BIT_NAMES.filter((_, i) => (w >> i) & 1).join(",") || "-";

class StepError extends Error {}
function check(cond, what) {
  if (!cond) throw new StepError(what);
}
function pass(what) {
  passed += 1;
  console.log(`PASS: ${step}: ${what}`);
}

// ---- the register map as an integrator gets it ----
function loadMap() {
  const csv = execFileSync(epa, ["registers", path.join(src, "registers/epa.csv"), "--csv", "-"],
    { encoding: "utf8", timeout: 30000, stdio: ["ignore", "pipe", "ignore"] });
  const lines = csv.trim().split("\n");
  const header = lines[0].split(",");
  check(header.slice(0, 6).join(",") === "point,table,address,reference,type,word_order",
    `unexpected CSV header ${lines[0]}`);
  const map = new Map();
  for (const line of lines.slice(1)) {
    const f = line.split(","); // the first six columns never hold a comma or a quote
    map.set(`${f[0]}/${f[1]}`, { table: f[1], address: Number(f[2]), reference: f[3], type: f[4], wordOrder: f[5] });
  }
  return map;
}
let map = null;
function at(name, table) {
  const p = map.get(`${name}/${table}`); // by name and table: `reset` is a holding register and a coil
  check(p !== undefined, `point ${name} (${table}) is not in the exported map`);
  if (p.type === "float32" || p.type === "uint32") check(p.wordOrder === "ABCD", `${name}: word order ${p.wordOrder}`);
  return p.address;
}

// ---- float32 / uint32, ABCD ----
function f32Words(v) {
  const b = Buffer.alloc(4);
  b.writeFloatBE(v, 0);
  return [b.readUInt16BE(0), b.readUInt16BE(2)];
}
const u32Words = (v) => [(v >>> 16) & 0xffff, v & 0xffff];

// ---- Modbus calls, each naming what failed ----
async function call(what, fn) {
  try {
    return await fn();
  } catch (e) {
    const code = e && e.modbusCode !== undefined ? ` (Modbus exception ${e.modbusCode})` : "";
    throw new StepError(`${what}: ${e && e.message ? e.message : e}${code}`);
  }
}
const c = new ModbusRTU();
const readH = (name, n = 1) => call(`read ${name}`, () => c.readHoldingRegisters(at(name, "holding"), n));
const readI = (name, n = 1) => call(`read ${name}`, () => c.readInputRegisters(at(name, "input"), n));
const f32In = async (name) => (await readI(name, 2)).buffer.readFloatBE(0);
const u16In = async (name) => (await readI(name)).data[0];
const u16H = async (name) => (await readH(name)).data[0];
const status = () => u16In("status_word");
const writeU16 = (name, v) => call(`write ${name} ${v} (FC6)`, () => c.writeRegister(at(name, "holding"), v));
const writeF32 = (name, v) => call(`write ${name} ${v} (FC16, ABCD)`, () => c.writeRegisters(at(name, "holding"), f32Words(v)));

async function waitStatus(want, clear, timeoutMs, what, since = now()) {
  const deadline = now() + timeoutMs;
  let w = null;
  while (now() < deadline) {
    w = await status();
    if ((w & want) === want && !(w & clear)) return { word: w, ms: now() - since };
    await sleep(10);
  }
  const pos = await f32In("position_mm");
  throw new StepError(`${what}: status_word did not have ${bits(want)} set and ${bits(clear)} clear within ` +
    `${timeoutMs} ms; last ${bits(w)}, position ${pos.toFixed(2)} mm, mode ${await u16H("mode")}`);
}
async function waitStanding(timeoutMs, what) {
  const deadline = now() + timeoutMs;
  let last = await f32In("position_mm");
  while (now() < deadline) {
    await sleep(300);
    const p = await f32In("position_mm");
    if (Math.abs(p - last) <= 0.2) return p;
    last = p;
  }
  throw new StepError(`${what}: the piston did not stand still within ${timeoutMs} ms (last ${last.toFixed(2)} mm)`);
}
async function startHandshake(what) {
  const t0 = now();
  await writeU16("control_word", CW.start);
  const a = await waitStatus(S.ack, 0, 2000, `${what}: ack after start=1`, t0);
  check(a.word & (S.moving | S.in_position), `${what}: ack without moving or in_position: ${bits(a.word)}`);
  check(!(a.word & S.target_reached), `${what}: target_reached still set once the start is acknowledged: ${bits(a.word)}`);
  const t1 = now();
  await writeU16("control_word", 0);
  const b = await waitStatus(0, S.ack, 2000, `${what}: ack clears after start=0`, t1);
  pass(`${what}: ack ${a.ms} ms after start=1 (${bits(a.word)}), cleared ${b.ms} ms after start=0`);
  return t0;
}

// ---- the heartbeat: a second connection, as a supervising HMI keeps one ----
const hb = { client: new ModbusRTU(), count: 0, paused: false, errors: [], timer: null, busy: false };
async function beat() {
  if (hb.paused || hb.busy) return;
  hb.busy = true;
  hb.count += 1;
  try {
    await hb.client.writeRegisters(at("heartbeat", "holding"), u32Words(hb.count));
  } catch (e) {
    hb.errors.push(String(e && e.message ? e.message : e));
  }
  hb.busy = false;
}

async function main() {
  step = "connect";
  await call(`connect to ${host}:${port}`, () => c.connectTCP(host, { port }));
  c.setID(UNIT);
  c.setTimeout(2000);

  step = "register map";
  map = loadMap();
  for (const [n, t] of [["setpoint_mm", "holding"], ["mode", "holding"], ["manual_valve_v", "holding"],
    ["heartbeat", "holding"], ["unlock", "holding"], ["control_word", "holding"], ["record_select", "holding"],
    ["record1_target_mm", "holding"], ["record2_target_mm", "holding"], ["position_mm", "input"],
    ["status_word", "input"], ["move_end", "input"], ["speed_mm_s", "input"], ["reference_mm", "input"],
    ["fault_code", "input"], ["fault_history_count", "input"], ["fault_0_code", "input"], ["jog_minus", "coil"],
    ["fault_latched", "discrete"]]) at(n, t);
  check(at("record1_controller", "holding") - at("record1_target_mm", "holding") === 6, "record layout");
  check(at("fault_0_valve_v", "input") - at("fault_0_code", "input") === 8, "fault history entry layout");
  pass(`${map.size} points from \`epa registers --csv\`; status_word at input ${at("status_word", "input")}, ` +
    `control_word at holding ${at("control_word", "holding")}`);

  await call("connect the heartbeat connection", () => hb.client.connectTCP(host, { port }));
  hb.client.setID(UNIT);
  hb.client.setTimeout(2000);
  await beat();
  hb.timer = setInterval(beat, 200);

  step = "FC43/14 device identification";
  const version = execFileSync(epa, ["--version"], { encoding: "utf8", timeout: 10000 }).trim();
  check(/^epa \d+\.\d+\.\d+$/.test(version), `epa --version printed ${version}`);
  const id = await call("readDeviceIdentification(1, 0)", () => c.readDeviceIdentification(1, 0));
  check(id.data[2] === version.split(" ")[1], `MajorMinorRevision ${JSON.stringify(id.data[2])}, expected ${version}`);
  check(id.data[1] === "epa", `ProductCode ${JSON.stringify(id.data[1])}`);
  pass(`objects ${JSON.stringify(id.data)}, conformity 0x${id.conformityLevel.toString(16)}`);

  step = "enable (mode RUN)";
  let w = await status();
  check((w & (S.ready | S.run_enabled | S.fault_latched)) === S.ready, `at start: ${bits(w)}`);
  let t0 = now();
  await writeU16("mode", 1);
  let r = await waitStatus(S.ready | S.run_enabled | S.in_position, S.moving, 2000, "mode RUN", t0);
  check(Math.abs(await f32In("position_mm")) <= 1, "RUN holds the piston where it is (0 mm)");
  pass(`run_enabled and in_position ${r.ms} ms after mode 1 (${bits(r.word)})`);

  step = "position record";
  const key = BigInt("0x" + UNLOCK_KEY);
  const keyWords = [48n, 32n, 16n, 0n].map((s) => Number((key >> s) & 0xffffn));
  await call("unlock (FC16, 4 registers)", () => c.writeRegisters(at("unlock", "holding"), keyWords));
  const rec1 = [...f32Words(150), ...f32Words(0), ...f32Words(2), 255];
  await call("record 1 in one FC16", () => c.writeRegisters(at("record1_target_mm", "holding"), rec1));
  const back = await call("read record 1", () => c.readHoldingRegisters(at("record1_target_mm", "holding"), 7));
  check(JSON.stringify(back.data) === JSON.stringify(rec1), `record 1 reads back ${back.data}, wrote ${rec1}`);
  check(back.buffer.readFloatBE(0) === 150, "record 1 target decodes as 150 with readFloatBE");
  const rec2 = [...f32Words(40), ...f32Words(60), ...f32Words(0), 3]; // law 3: pp-traj, made for a profile
  await call("record 2 in one FC16", () => c.writeRegisters(at("record2_target_mm", "holding"), rec2));
  await writeU16("record_select", 1);
  pass("unlocked; record 1 (150 mm, no speed limit, 2 mm window, running law) and record 2 (40 mm at 60 mm/s) written and read back");

  step = "start handshake";
  t0 = await startHandshake("start record 1");
  r = await waitStatus(S.in_position | S.target_reached, S.moving | S.ack, 15000, "record 1: in_position + target_reached", t0);
  let pos = await f32In("position_mm");
  check(Math.abs(pos - 150) <= 2, `in position at ${pos} mm, record 1's target 150 mm +- 2 mm`);
  check((await u16In("move_end")) === 0, "move_end: 0 (complete)");
  pass(`in_position + target_reached ${r.ms} ms after start=1, at ${pos.toFixed(2)} mm`);

  step = "halt";
  await writeU16("record_select", 2);
  t0 = await startHandshake("start record 2");
  let deadline = now() + 5000;
  while ((await f32In("position_mm")) > 110 && now() < deadline) await sleep(20);
  const atHalt = await f32In("position_mm");
  check(atHalt < 125, `record 2 moves down before the halt (at ${atHalt} mm)`);
  const t1 = now();
  await writeU16("control_word", CW.halt);
  const h1 = await waitStatus(S.halted, 0, 2000, "halted after halt=1", t1);
  // Stood where it braked to, short of the record's target: halted, not in position (the target's).
  const h2 = await waitStatus(S.halted, S.moving | S.in_position, 5000, "halted, standing short of the target, not in position", t1);
  await writeU16("control_word", 0);
  const rest = await waitStanding(5000, "after the halt");
  check((await u16In("move_end")) === 2, "move_end: 2 (halted)");
  check(!(h2.word & S.target_reached), `target_reached after a halt: ${bits(h2.word)}`);
  check(rest > 55, `the piston stopped short of record 2's 40 mm (stands at ${rest} mm)`);
  check(Math.abs(rest - (await f32In("reference_mm"))) <= 2, "it holds where the reference stopped");
  pass(`halt at ${atHalt.toFixed(2)} mm (${t1 - t0} ms into the move): halted after ${h1.ms} ms, standing ` +
    `${h2.ms} ms after halt=1 at ${rest.toFixed(2)} mm, not in position`);

  step = "jog in MANUAL";
  t0 = now();
  await writeU16("mode", 2);
  r = await waitStatus(S.manual_mode | S.ready, S.run_enabled, 2000, "MANUAL", t0);
  const before = await waitStanding(5000, "before the jog");
  t0 = now();
  await writeU16("control_word", CW.jog_plus);
  const j = await waitStatus(S.jogging | S.moving, 0, 2000, "jogging after jog_plus", t0);
  const speeds = [];
  while (now() - t0 < 1500) {
    await sleep(300);
    await writeU16("control_word", CW.jog_plus); // the keep-alive
    speeds.push(await f32In("speed_mm_s"));
  }
  await writeU16("control_word", 0);
  const rel = await waitStatus(S.manual_mode, S.jogging | S.moving, 2000, "jog released: jogging clears");
  const after = await waitStanding(5000, "after releasing jog_plus");
  const top = Math.max(...speeds);
  check(top >= 0.5 * JOG_SPEED_MM_S && top <= 1.5 * JOG_SPEED_MM_S, `jog speed ${speeds.map((s) => s.toFixed(1))} mm/s`);
  check(after - before > 15, `jog_plus for 1.5 s moved the piston up (${before} -> ${after} mm)`);
  pass(`jog_plus: jogging after ${j.ms} ms, top speed ${top.toFixed(1)} mm/s, ${before.toFixed(2)} -> ` +
    `${after.toFixed(2)} mm, braked ${rel.ms} ms after release`);
  hb.paused = true; // the client goes silent: no heartbeat, no control word write
  let lapse;
  try {
    t0 = now();
    await call("coil jog_minus 1 (FC5)", () => c.writeCoil(at("jog_minus", "coil"), true));
    await waitStatus(S.jogging | S.moving, 0, 2000, "jogging after coil jog_minus", t0);
    lapse = await waitStatus(S.manual_mode, S.jogging | S.moving, (JOG_KEEPALIVE_S + 2) * 1000,
      "jog_minus without keep-alive brakes by itself", t0);
  } finally {
    hb.paused = false;
  }
  await call("coil jog_minus 0 (FC5)", () => c.writeCoil(at("jog_minus", "coil"), false));
  const below = await waitStanding(5000, "after the keep-alive lapsed");
  check(lapse.ms >= JOG_KEEPALIVE_S * 1000 - 50, `braked after ${lapse.ms} ms, before jog_keepalive_s`);
  check(below < after, "jog_minus moved the piston down");
  check((await u16H("mode")) === 2, "still MANUAL after a lapsed jog");
  pass(`jog_minus (coil) with the client silent braked ${lapse.ms} ms after the write, at ${below.toFixed(2)} mm`);

  step = "fault history";
  const countBefore = (await readI("fault_history_count", 2)).buffer.readUInt32BE(0);
  t0 = now();
  await writeF32("manual_valve_v", 1.5);
  const f = await waitStatus(S.fault_latched, 0, 15000, `soft-limit fault (piston past ${SOFT_MAX_MM} mm)`, t0);
  check(!(f.word & S.ready), `ready while a fault is latched: ${bits(f.word)}`);
  check((await u16H("mode")) === 3, "mode 3 (fault)");
  check((await u16In("fault_code")) === 3, "fault_code 3 (soft limit)");
  const di = await call("read discrete fault_latched", () => c.readDiscreteInputs(at("fault_latched", "discrete"), 1));
  check(di.data[0] === true, "discrete input fault_latched");
  const t2 = now();
  await writeU16("control_word", CW.reset);
  const rs = await waitStatus(S.ready, S.fault_latched, 2000, "ready after the reset bit", t2);
  await writeU16("control_word", 0);
  check((await u16H("mode")) === 0, "mode 0 (stop) after the reset");
  // An HMI reads the history once the fault is gone (ready again): it should hold the fault then.
  const countAtReady = (await readI("fault_history_count", 2)).buffer.readUInt32BE(0);
  const t3 = now();
  let count = countAtReady;
  while (count === countBefore && now() - t3 < 2000) {
    await sleep(5);
    count = (await readI("fault_history_count", 2)).buffer.readUInt32BE(0);
  }
  const lagMs = now() - t3;
  check(count === countBefore + 1, `fault_history_count ${count} (waited up to 2 s), expected ${countBefore + 1}`);
  const e = (await readI("fault_0_code", 10)).buffer;
  const entry = { code: e.readUInt16BE(0), mode: e.readUInt16BE(2), time: e.readUInt32BE(4), position: e.readFloatBE(8),
    setpoint: e.readFloatBE(12), valve: e.readFloatBE(16) };
  check(entry.code === 3, `newest entry: code ${entry.code}, expected 3`);
  check(entry.mode === 2, `newest entry: mode ${entry.mode}, expected 2 (manual)`);
  check(Math.abs(entry.time - Date.now() / 1000) <= 60, `newest entry: time ${entry.time} is not now`);
  check(entry.position >= SOFT_MAX_MM - 1 && entry.position <= SOFT_MAX_MM + 10, `newest entry: position ${entry.position}`);
  check(Math.abs(entry.valve - 1.5) < 1e-3, `newest entry: valve ${entry.valve}`);
  pass(`soft-limit latched ${f.ms} ms after valve 1.5 V, reset bit -> ready in ${rs.ms} ms; count at ready ` +
    `${countAtReady}, ${count} after ${lagMs} ms; newest ${JSON.stringify(entry)}`);

  check(countAtReady === countBefore + 1, `DEVICE: fault_history_count read right after the reset (status ready, ` +
    `mode 0) was still ${countAtReady}; the reset fault was counted ${lagMs} ms later`);

  step = "heartbeat";
  check(hb.errors.length === 0, `heartbeat writes failed: ${hb.errors.slice(0, 3)}`);
  pass(`${hb.count} heartbeat writes answered`);
}

const overall = setTimeout(() => {
  console.error(`FAIL: ${step}: the whole flow did not finish within 90 s`);
  process.exit(1);
}, 90000);

main().then(
  () => 0,
  (e) => {
    console.error(`FAIL: ${step}: ${e instanceof StepError ? e.message : (e && e.stack) || e}`);
    return 1;
  },
).then(async (rc) => {
  clearInterval(hb.timer);
  clearTimeout(overall);
  for (const cl of [c, hb.client]) {
    try {
      if (cl.isOpen) await Promise.race([cl.close(), sleep(1000)]);
    } catch (_) { /* closing is best effort */ }
  }
  console.log(`${passed} passed, ${rc} failed`);
  process.exit(rc);
});
