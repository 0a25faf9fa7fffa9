// The status page: polls /api/status and /api/trend every 250 ms, the slower-changing
// /api/moves, /api/tuning, /api/audit, /api/health and /api/faults every 2 s, and draws with Chart.js (Debian's
// libjs-chart.js, served at /vendor/chart.js). No build step.
"use strict";

const FAST_MS = 250, SLOW_MS = 2000;
const $ = (id) => document.getElementById(id);
// A move's figure that does not apply to how it ended (overshoot of a halted move, the settling
// of one cut short) comes as null: "n/a".
const fmt = (v, digits = 2) => (v === null || v === undefined || !Number.isFinite(v)) ? "n/a" : v.toFixed(digits);
const num = (v, digits = 2) => (v === null || v === undefined || !Number.isFinite(v)) ? "–" : v.toFixed(digits);
const setText = (id, text) => { const e = $(id); if (e && e.textContent !== text) e.textContent = text; };

let positionChart = null, valveChart = null, healthChart = null;

function makeCharts() {
  if (typeof Chart === "undefined") return;  // Chart.js missing: numbers only
  const common = {
    animation: false, responsive: true, maintainAspectRatio: false, parsing: false, normalized: true,
    interaction: { mode: "nearest", intersect: false },
    elements: { point: { radius: 0 }, line: { borderWidth: 2, tension: 0 } },
    scales: { x: { type: "linear", title: { display: true, text: "time, s" }, ticks: { maxTicksLimit: 8 } } },
    plugins: { legend: { labels: { boxWidth: 12 } } },
  };
  positionChart = new Chart($("position-chart"), {
    type: "line",
    data: { datasets: [
      { label: "setpoint, mm", data: [], borderColor: "#8a94a6", borderDash: [6, 4], stepped: true },
      { label: "position, mm", data: [], borderColor: "#1f5fbf" },
    ] },
    options: { ...common, scales: { ...common.scales, y: { title: { display: true, text: "mm" } } } },
  });
  valveChart = new Chart($("valve-chart"), {
    type: "line",
    data: { datasets: [
      { label: "dead zone b_l", data: [], borderColor: "rgba(198,40,40,0.5)", borderWidth: 1, borderDash: [3, 3] },
      { label: "dead zone b_r", data: [], borderColor: "rgba(198,40,40,0.5)", borderWidth: 1, borderDash: [3, 3],
        backgroundColor: "rgba(198,40,40,0.10)", fill: "-1" },
      { label: "valve, V", data: [], borderColor: "#b7791f" },
    ] },
    options: { ...common, scales: { ...common.scales, y: { title: { display: true, text: "V" } } },
               plugins: { legend: { labels: { boxWidth: 12, filter: (item) => item.text !== "dead zone b_l" } } } },
  });
  valveChart.data.datasets[1].label = "dead zone [b_l, b_r]";
  healthChart = new Chart($("health-chart"), {
    type: "line",
    data: { datasets: HEALTH_EFFECTS.map(([, label, color]) => ({ label, data: [], borderColor: color })) },
    options: { ...common, scales: { x: { type: "linear", title: { display: true, text: "move" }, ticks: { maxTicksLimit: 8 } },
                                    y: { title: { display: true, text: "ratio to commissioned" } } } },
  });
}

// The effects the monitor estimates, as /api/health names them, with the chart's label and colour.
const HEALTH_EFFECTS = [["static_friction", "friction", "#c62828"], ["gain_change", "flow gain", "#1f5fbf"],
  ["deadzone_shift", "dead band", "#b7791f"], ["valve_lag", "spool lag", "#2e7d32"], ["input_delay", "dead time", "#6a1b9a"]];

// Model health (GET /api/health): the verdict, and each effect's estimate over the judged moves.
function showHealth(h) {
  const card = $("health");
  card.dataset.state = h.state;
  const badge = $("h-state");
  setText("h-state", h.state);
  badge.className = "badge health-" + h.state;
  setText("h-size", h.size || (h.state === "ok" ? "nothing beyond its tolerance" : "–"));
  setText("h-ratio", h.ratio === null ? "–" : `${num(h.ratio, 2)} (${num(h.value, 3)} ${h.unit}, commissioned ${num(h.commissioned, 3)})`);
  setText("h-moves", `${h.moves_since_onset} / ${h.moves_seen}` + (h.moves_dropped ? ` (${h.moves_dropped} not judged: busy)` : ""));
  setText("h-reason", h.reason);
  if (!healthChart) return;
  HEALTH_EFFECTS.forEach(([effect], i) => {
    healthChart.data.datasets[i].data = h.trend.map((j) => {
      const e = j.estimates.find((x) => x.effect === effect);
      return { x: j.move, y: e ? e.ratio : null };
    });
  });
  healthChart.update("none");
}

async function getJson(path) {
  const res = await fetch(path, { cache: "no-store" });
  if (!res.ok) throw new Error(`${path}: HTTP ${res.status}`);
  return res.json();
}

function showStatus(s) {
  const mode = $("mode");
  setText("mode", s.mode);
  mode.className = "badge " + s.mode;
  setText("controller", s.controller_name);
  setText("version", s.version);
  setText("uptime", `up ${num(s.time_s, 0)} s` + (s.mode === "excite" ? ` \u2014 excitation: ${num(s.excite_left_s, 0)} s left` : ""));
  const fault = $("fault");
  fault.hidden = s.mode !== "fault";
  if (s.mode === "fault") { setText("fault-code", s.fault); setText("fault-text", s.fault_text || ""); }
  // Warnings the server may report; an older server without the field shows none.
  $("warn-any-address").hidden = s.any_address_may_command !== true;
  $("warn-disk-low").hidden = !(s.disk_low === true || (s.store && s.store.disk_low === true));
  setText("position", num(s.position_mm, 1));
  setText("setpoint", num(s.setpoint_mm, 1));
  setText("error", num(s.error_mm, 2));
  setText("valve", num(s.valve_v, 3));
  const L = s.loop;
  setText("s-jitter", `${num(L.jitter_p50_us, 0)} / ${num(L.jitter_p99_us, 0)} / ${num(L.jitter_max_us, 0)} µs`);
  setText("s-wake", `${num(L.wake_p99_us, 0)} µs`);
  setText("s-compute", `${num(L.compute_p99_us, 0)} µs`);
  setText("s-cycles", `${L.cycles} / ${L.overruns}`);
  setText("s-faults", `${s.counters.faults} / ${s.counters.io_errors}`);
  setText("s-commands", `${s.counters.commands_applied} / ${s.counters.commands_rejected}`);
  setText("s-heartbeat", String(s.heartbeat));
  setText("s-modbus", s.modbus.enabled ? `${s.modbus.clients} / ${s.modbus.requests}` : "off");
  setText("s-store", !s.store.enabled ? "off"
    : `${s.store.saved} / ${s.store.accepted}` + (s.store.ok ? "" : ` \u2014 NOT SAVING: ${s.store.last_error}`));
  setText("s-tuning-set", s.store.enabled ? s.store.tuning_set : "\u2013");
  showWebLogin(s);
  const m = s.last_move;
  setText("last-move-head", m ? `#${m.number}: ${num(m.from_mm, 1)} → ${num(m.to_mm, 1)} mm, ${m.controller}, ${m.end.replace("_", " ")}`
    : "none yet");
  setText("lm-rise", m ? `${fmt(m.rise_s, 3)}${m.rise_s === null ? "" : " s"}` : "–");
  setText("lm-settling", m ? `${fmt(m.settling_s, 3)}${m.settling_s === null ? "" : " s"}` : "–");
  setText("lm-ess", m ? `${fmt(m.ess_mm, 2)}${m.ess_mm === null ? "" : " mm"}` : "–");
  setText("lm-overshoot", m ? `${fmt(m.overshoot_pct, 1)}${m.overshoot_pct === null ? "" : " %"}` : "–");
  showStatusBits(s);
  document.dispatchEvent(new CustomEvent("epa-status", { detail: s }));  // commands.js
  document.body.dataset.positionMm = Number.isFinite(s.position_mm) ? s.position_mm.toFixed(3) : "";
  document.body.dataset.mode = s.mode;
}

// The status word's bits as lamps (data-on "1"/"0" for the browser test), the word in hex.
function showStatusBits(s) {
  if (s.status_word === undefined) return;
  setText("sb-word", "0x" + s.status_word.toString(16).toUpperCase().padStart(4, "0"));
  for (const [bit, on] of Object.entries(s.status_bits)) {
    const lamp = $(`sb-${bit}`);
    if (!lamp) continue;
    lamp.classList.toggle("on", on);
    lamp.dataset.on = on ? "1" : "0";
  }
}

function showTrend(t) {
  const n = t.t_s.length;
  document.body.dataset.trendPoints = String(n);
  if (!positionChart) return;
  const sp = new Array(n), pos = new Array(n), u = new Array(n);
  for (let i = 0; i < n; ++i) {
    sp[i] = { x: t.t_s[i], y: t.setpoint_mm[i] };
    pos[i] = { x: t.t_s[i], y: t.position_mm[i] };
    u[i] = { x: t.t_s[i], y: t.valve_v[i] };
  }
  const x0 = n ? t.t_s[0] : 0, x1 = n ? t.t_s[n - 1] : 1;
  const xmin = Math.max(x0, x1 - t.window_s);
  for (const c of [positionChart, valveChart]) { c.options.scales.x.min = xmin; c.options.scales.x.max = x1; }
  positionChart.data.datasets[0].data = sp;
  positionChart.data.datasets[1].data = pos;
  const bl = t.dead_zone.b_l, br = t.dead_zone.b_r;
  valveChart.data.datasets[0].data = n && bl !== null ? [{ x: x0, y: bl }, { x: x1, y: bl }] : [];
  valveChart.data.datasets[1].data = n && br !== null ? [{ x: x0, y: br }, { x: x1, y: br }] : [];
  valveChart.data.datasets[2].data = u;
  positionChart.update("none");
  valveChart.update("none");
}

function showMoves(d) {
  const body = $("moves").tBodies[0];
  const rows = d.moves.map((m) => `<tr title="ended: ${m.end.replace("_", " ")}"><td>${m.number}</td><td>${num(m.from_mm, 0)} → ${num(m.to_mm, 0)}</td>` +
    `<td>${m.controller}</td><td>${fmt(m.rise_s, 3)}</td><td>${fmt(m.settling_s, 3)}</td>` +
    `<td>${fmt(m.ess_mm, 2)}</td><td>${fmt(m.overshoot_pct, 1)}</td></tr>`);
  const html = rows.length ? rows.join("") : `<tr><td colspan="7" class="muted">no moves yet</td></tr>`;
  if (body.innerHTML !== html) body.innerHTML = html;
}

function showTuning(t) {
  setText("t-m", `${num(t.m_r, 4)} / ${num(t.m_l, 4)}`);
  setText("t-b", `${num(t.b_r, 4)} / ${num(t.b_l, 4)} V`);
  setText("t-lc", `${num(t.lc_mm, 2)} mm`);
  setText("t-ts", `${num(t.Ts * 1000, 2)} ms`);
  const poly = (c) => c.map((v) => (v === null ? "–" : Number(v.toPrecision(5)))).join(", ");
  setText("t-f", poly(t.F));
  setText("t-g", poly(t.G));
  setText("t-h", poly(t.H));
  setText("t-traj", `${num(t.traj_speed_fraction * 100, 0)} % / ${num(t.traj_bandwidth_rad_s, 1)} rad/s / ${num(t.traj_hold_band_mm, 3)} mm`);
}

const escapeHtml = (s) => String(s).replace(/[&<>"']/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&#39;" }[c]));

// Times as everywhere else in the appliance: ISO 8601, UTC.
const isoUtc = (ms) => new Date(ms).toISOString().replace("T", " ").replace(/\.\d+Z$/, "Z");
// An audited value as its point means it: the law and the mode by name, whole numbers as they are.
const LAWS = ["pp", "pp-ngidz", "pp-ffidz", "pp-traj"], MODES = ["stop", "run", "manual", "fault", "excite"];
function auditValue(point, v) {
  if (v === null || v === undefined || !Number.isFinite(v)) return "–";
  const names = point === "controller" ? LAWS : point === "mode" ? MODES : null;
  if (names && Number.isInteger(v) && names[v]) return `${v} ${names[v]}`;
  return Number.isInteger(v) ? String(v) : String(Number(v.toFixed(4)));
}

function showAudit(a) {
  const body = $("audit").tBodies[0];
  const rows = a.entries.map((e) => `<tr><td>${isoUtc(e.unix_time_ms)}</td>` +
    `<td>${escapeHtml(e.source)}</td><td>${escapeHtml(e.point)}</td><td>${auditValue(e.point, e.old_value)}</td>` +
    `<td>${auditValue(e.point, e.new_value)}</td></tr>`);
  const html = rows.length ? rows.join("") : `<tr><td colspan="5" class="muted">no changes yet</td></tr>`;
  if (body.innerHTML !== html) body.innerHTML = html;
}

// Who commands from this page: the token, or over HTTPS this browser's client certificate by its
// role (/api/status client_certificate); with a role that may, the token fields are not needed.
function showWebLogin(s) {
  const cert = s.client_certificate;
  const operates = !!cert && (cert.rights === "operate" || cert.rights === "tune");
  const tunes = !!cert && cert.rights === "tune";
  const who = cert ? `certificate ${cert.subject}, role ${cert.role || "none"}: ${cert.rights || "not in the role table"}` : "";
  setText("s-web", operates ? `enabled (${who})` : s.commands_enabled ? "enabled (token)" : cert ? `read-only (${who})` : "read-only");
  $("cmd-token").placeholder = operates ? "not needed: your certificate" : "[web] token";
  $("c-token").required = !tunes;
  $("c-token").placeholder = tunes ? "not needed: your certificate" : "[web] token";
}

// Commissioning: start and abort need the [web] token (sent as a bearer token, kept only in this
// page); the progress is polled with the slow data, and every 500 ms while a run is under way.
let commissionRunning = false;

function showCommission(c) {
  commissionRunning = c.running;
  const bar = $("c-bar");
  if (bar) bar.style.width = `${Math.max(0, Math.min(100, c.percent || 0)).toFixed(0)}%`;
  setText("c-message", c.running ? `${c.stage}: ${c.message}` : (c.verdict === "none" ? "idle" : c.message));
  $("commission").dataset.verdict = c.verdict;
  $("c-start").disabled = c.running;
  $("c-abort").disabled = !c.running;
  $("c-links").hidden = c.running || c.verdict === "none";
}

async function commissionCommand(path, body) {
  const res = await fetch(path, {
    method: "POST", cache: "no-store", body,
    headers: { "Authorization": `Bearer ${$("c-token").value}`, "Content-Type": "application/json" },
  });
  const answer = await res.json().catch(() => ({}));
  setText("c-answer", res.ok ? "accepted" : `refused (${res.status}): ${answer.error || res.statusText}`);
  pollCommission();
}

async function pollCommission() {
  try { showCommission(await getJson("/api/commission")); } catch (e) { /* no service, or no connection */ }
}

function commissionPanel() {
  $("c-form").addEventListener("submit", (e) => { e.preventDefault(); commissionCommand("/api/commission", $("c-spec").value); });
  $("c-abort").addEventListener("click", () => commissionCommand("/api/commission/abort", ""));
  (async function loop() {
    await pollCommission();
    setTimeout(loop, commissionRunning ? 500 : SLOW_MS);
  })();
}

// The fault history (GET /api/faults): every fault with its cause, newest first, polled with the
// slow data on its own timer; a fault reset at once is still listed.
function showFaults(d) {
  const card = $("fault-history");
  card.dataset.count = String(d.count);
  setText("fh-head", d.count ? `${d.count} since the store was created; newest first` : "newest first");
  const body = $("faults").tBodies[0];
  const rows = d.faults.map((f) => `<tr class="fh-cause"><td>${isoUtc(f.time_ms)}</td>` +
    `<td class="fh-name">${escapeHtml(f.name)}</td><td>${escapeHtml(f.mode)}</td><td>${num(f.position_mm, 1)} mm</td>` +
    `<td>${num(f.setpoint_mm, 1)} mm</td><td>${num(f.valve_v, 3)} V</td></tr>` +
    `<tr><td colspan="6" class="fh-text">${escapeHtml(f.text)}</td></tr>`);
  const html = rows.length ? rows.join("") : `<tr><td colspan="6" class="muted">no faults recorded</td></tr>`;
  if (body.innerHTML !== html) body.innerHTML = html;
}

async function pollFaults() {
  try {
    showFaults(await getJson("/api/faults"));
  } catch (e) {
    // the fast poll shows the connection state
  } finally {
    setTimeout(pollFaults, SLOW_MS);
  }
}

function linkState(ok, message) {
  const link = $("link");
  link.classList.toggle("down", !ok);
  setText("link", ok ? "live" : message);
}

async function fast() {
  try {
    const [s, t] = await Promise.all([getJson("/api/status"), getJson("/api/trend")]);
    showStatus(s);
    showTrend(t);
    linkState(true);
  } catch (e) {
    linkState(false, "no connection");
  } finally {
    setTimeout(fast, FAST_MS);
  }
}

async function slow() {
  try {
    const [m, t, a, h] = await Promise.all([getJson("/api/moves"), getJson("/api/tuning"), getJson("/api/audit"), getJson("/api/health")]);
    showMoves(m);
    showTuning(t);
    showAudit(a);
    showHealth(h);
  } catch (e) {
    // the fast poll shows the connection state
  } finally {
    setTimeout(slow, SLOW_MS);
  }
}

makeCharts();
fast();
slow();
commissionPanel();
pollFaults();
