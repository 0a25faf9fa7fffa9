// The position-record table (GET /api/records, every 2 s, read-only without a token) and, when the
// server says commands are enabled (/api/status commands_enabled), the command panel and the
// record editor. Every command is a POST with the [web] token as a bearer token; the token lives
// only in the panel's password input (never stored). The server's answer is shown as it is, so a
// refusal reads the way the write gate worded it. app.js hands each status over as an
// "epa-status" event.
"use strict";

(function () {
  const RECORDS_MS = 2000, JOG_KEEPALIVE_MS = 300;
  const START = 1, HALT = 2;  // control word bits (runtime/axis_words.hpp)
  const $ = (id) => document.getElementById(id);
  const text = (v, digits, unit) => (v === null || v === undefined || !Number.isFinite(v)) ? "–" : `${v.toFixed(digits)} ${unit}`;
  const esc = (s) => String(s).replace(/[&<>"']/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&#39;" }[c]));

  let status = null;        // the last /api/status
  let records = [];         // the last /api/records .records
  let enabled = false;      // commands_enabled, as the server last said
  let heartbeat = null;     // the jog keep-alive's next heartbeat value

  // One command: POST `body` (an object) to `path` with the token; shows the answer in `answerId`
  // ("accepted", or "refused (401): <the server's error>"). Resolves to whether it was accepted.
  async function send(path, body, what, answerId = "cmd-answer", quiet = false) {
    const answer = $(answerId);
    let res, reply = {};
    try {
      res = await fetch(path, {
        method: "POST", cache: "no-store", body: JSON.stringify(body),
        headers: { "Authorization": `Bearer ${$("cmd-token").value}`, "Content-Type": "application/json" },
      });
      reply = await res.json().catch(() => ({}));
    } catch (e) {
      answer.textContent = `${what}: no connection to the appliance`;
      answer.dataset.status = "0";
      return false;
    }
    if (!res.ok || !quiet) {
      answer.textContent = res.ok ? `${what}: accepted` : `${what}: refused (${res.status}): ${reply.error || res.statusText}`;
      answer.dataset.status = String(res.status);
      answer.classList.toggle("refused", !res.ok);
    }
    return res.ok;
  }
  const points = (body, what, quiet) => send("/api/points", body, what, "cmd-answer", quiet);

  // An edge of a control-word bit: set, then clear (the gate acts on the rising edge); cleared
  // first when a client left it set, or the set would be no edge.
  async function edge(bit, name, extra, what) {
    if (status && (status.control_word & bit)) await points({ [name]: 0 }, what, true);
    const ok = await points({ ...extra, [name]: 1 }, what);
    await points({ [name]: 0 }, what, true);
    return ok;
  }

  // Jog: held while the button is pressed. The bit is written once; while held a heartbeat every
  // 300 ms keeps the jog alive (the loop brakes a jog without one within [motion]
  // jog_keepalive_s). The heartbeat rather than the bit again: it is what a supervising client
  // already sends, and it is never audited.
  function jogButton(id, name) {
    const button = $(id);
    let timer = null;
    const release = () => {
      if (timer === null) return;
      clearInterval(timer);
      timer = null;
      button.classList.remove("held");
      points({ [name]: 0 }, `release ${name}`, true);
    };
    button.addEventListener("pointerdown", async (e) => {
      e.preventDefault();
      if (timer !== null) return;
      if (button.setPointerCapture && e.pointerId !== undefined) { try { button.setPointerCapture(e.pointerId); } catch (_) { /* synthetic */ } }
      button.classList.add("held");
      heartbeat = ((status ? status.heartbeat : 0) + 1) >>> 0;
      timer = setInterval(() => {
        heartbeat = (heartbeat + 1) >>> 0;
        points({ heartbeat }, name, true);
      }, JOG_KEEPALIVE_MS);
      if (!(await points({ [name]: 1 }, name))) release();
    });
    for (const ev of ["pointerup", "pointercancel", "lostpointercapture"]) button.addEventListener(ev, release);
    button.addEventListener("contextmenu", (e) => e.preventDefault());  // a long touch is a jog, not a menu
    window.addEventListener("blur", release);
  }

  function showRecords(d) {
    records = d.records;
    const card = $("records");
    card.dataset.recordSelect = String(d.record_select);
    $("rec-head").textContent = d.record_select ? `record ${d.record_select} selected` : "setpoint selected (record 0)";
    const rows = d.records.map((r) => `<tr data-record="${r.record}"${r.record === d.record_select ? ' class="selected"' : ""}>` +
      `<td>${r.record}</td><td>${text(r.target_mm, 1, "mm")}</td>` +
      `<td>${r.speed_mm_s ? text(r.speed_mm_s, 1, "mm/s") : "no limit"}</td>` +
      `<td>${r.window_mm ? text(r.window_mm, 2, "mm") : "default"}</td><td>${esc(r.controller)}</td><td>${esc(r.approach)}</td>` +
      `<td>${enabled ? `<button type="button" class="rec-edit" data-record="${r.record}">edit</button>` : ""}</td></tr>`);
    const body = $("record-table").tBodies[0];
    const html = rows.join("");
    if (body.innerHTML !== html) body.innerHTML = html;
  }

  async function pollRecords() {
    try {
      const res = await fetch("/api/records", { cache: "no-store" });
      if (res.ok) showRecords(await res.json());
    } catch (e) {
      // the fast poll shows the connection state
    } finally {
      setTimeout(pollRecords, RECORDS_MS);
    }
  }

  function editRecord(n) {
    const r = records.find((x) => x.record === n);
    if (!r) return;
    const form = $("rec-form");
    form.hidden = false;
    $("rec-number").value = String(n);
    $("rec-target").value = String(r.target_mm);
    $("rec-speed").value = String(r.speed_mm_s);
    $("rec-window").value = String(r.window_mm);
    $("rec-controller").value = r.controller;
    $("rec-approach").value = r.approach;
  }

  // The five fields of the record in the editor, in one POST (one gate group: all or nothing).
  function saveRecord() {
    const n = Number($("rec-number").value);
    const field = (id) => ($(id).value.trim() === "" ? NaN : Number($(id).value));
    send("/api/records", {
      record: n, target_mm: field("rec-target"), speed_mm_s: field("rec-speed"), window_mm: field("rec-window"),
      controller: $("rec-controller").value, approach: $("rec-approach").value,
    }, `record ${n}`, "rec-answer").then(pollOnce);
  }
  async function pollOnce() {
    try { const res = await fetch("/api/records", { cache: "no-store" }); if (res.ok) showRecords(await res.json()); } catch (e) { /* next poll */ }
  }

  function onStatus(s) {
    status = s;
    if (s.commands_enabled !== enabled) {
      enabled = s.commands_enabled;
      $("command").hidden = !enabled;
      if (!enabled) $("rec-form").hidden = true;
      pollOnce();  // the edit buttons come and go with the commands
    }
  }

  function init() {
    document.addEventListener("epa-status", (e) => onStatus(e.detail));
    $("cmd-form").addEventListener("submit", (e) => e.preventDefault());  // the buttons send; Enter does not post the form
    for (const mode of ["stop", "run", "manual"])
      $(`cmd-${mode}`).addEventListener("click", () => send("/api/mode", { mode }, `mode ${mode}`));
    $("cmd-move").addEventListener("click", () => {
      const v = $("cmd-setpoint").value.trim();
      send("/api/setpoint", { setpoint_mm: v === "" ? NaN : Number(v) }, `move to ${v} mm`);
    });
    $("cmd-start").addEventListener("click", () => {
      const n = Number($("cmd-record").value);
      edge(START, "start", { record_select: n }, n ? `start record ${n}` : "start (setpoint)");
    });
    $("cmd-halt").addEventListener("click", () => edge(HALT, "halt", {}, "halt"));
    $("cmd-reset").addEventListener("click", () => send("/api/reset", {}, "reset"));
    jogButton("cmd-jog-plus", "jog_plus");
    jogButton("cmd-jog-minus", "jog_minus");
    $("record-table").tBodies[0].addEventListener("click", (e) => {
      const b = e.target.closest("button.rec-edit");
      if (b) editRecord(Number(b.dataset.record));
    });
    $("rec-form").addEventListener("submit", (e) => { e.preventDefault(); saveRecord(); });
    $("rec-cancel").addEventListener("click", () => { $("rec-form").hidden = true; });
    pollRecords();
  }

  init();
})();
