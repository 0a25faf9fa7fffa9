// Added by command_panel_test.sh to a copy of the page, never shipped: drives the command panel
// through its DOM as a person would (types into its inputs, clicks its buttons, presses and
// releases the jog buttons with pointer events) following the steps in the URL's fragment,
// "#step;step;...", and reports on <body> for --dump-dom: data-probe ("done", or what went
// wrong), data-panel ("shown"/"hidden"), data-answers (the page's answer lines, " | "-joined).
// Whether a command took effect is for the test to ask the appliance, not this script.
"use strict";
(function () {
  const $ = (id) => document.getElementById(id);
  const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
  const answers = [];
  const report = (k, v) => { document.body.dataset[k] = v; };

  async function until(what, pred, tries = 200) {
    for (let i = 0; i < tries; ++i) { if (pred()) return; await sleep(50); }
    throw new Error(`timed out waiting for ${what}`);
  }
  function type(id, value) {
    const e = $(id);
    e.focus();
    e.value = value;
    e.dispatchEvent(new Event("input", { bubbles: true }));
    e.dispatchEvent(new Event("change", { bubbles: true }));
  }
  // Clicks (or does `act`), then waits for the page to write a new answer line in `answerId`.
  async function answered(answerId, act) {
    const el = $(answerId);
    let changed = false;
    const watch = new MutationObserver(() => { changed = true; });
    watch.observe(el, { childList: true, characterData: true, subtree: true, attributes: true });
    act();
    await until(`an answer in #${answerId}`, () => changed);
    watch.disconnect();
    answers.push(el.textContent);
  }
  const click = (id, answerId = "cmd-answer") => answered(answerId, () => $(id).click());
  // Real time, by the appliance's clock: the page runs on Chromium's virtual time, which jumps.
  async function appliance_seconds(s) {
    const t = async () => (await (await fetch("/api/status", { cache: "no-store" })).json()).time_s;
    const t0 = await t();
    while ((await t()) - t0 < s) await sleep(100);
  }
  function pointer(id, type) {
    $(id).dispatchEvent(new PointerEvent(type, { bubbles: true, cancelable: true, pointerId: 1, pointerType: "mouse", isPrimary: true, button: 0 }));
  }

  const steps = {
    // token=T: type it into the panel's token field
    token: (t) => type("cmd-token", decodeURIComponent(t)),
    // edit=N,target,speed,window,law: the row's edit button, the four fields, Save
    edit: async (args) => {
      const [n, target, speed, window, law] = args.split(",");
      await until(`the edit button of record ${n}`, () => document.querySelector(`#record-table button[data-record="${n}"]`));
      document.querySelector(`#record-table button[data-record="${n}"]`).click();
      type("rec-target", target);
      type("rec-speed", speed);
      type("rec-window", window);
      $("rec-controller").value = law;
      await click("rec-save", "rec-answer");
    },
    mode: (m) => click(`cmd-${m}`),
    setpoint: async (mm) => { type("cmd-setpoint", mm); await click("cmd-move"); },
    start: async (n) => { type("cmd-record", n); await click("cmd-start"); },
    halt: () => click("cmd-halt"),
    reset: () => click("cmd-reset"),
    // jog=plus,S: press, hold for S s of real time, release
    jog: async (args) => {
      const [dir, seconds] = args.split(",");
      const id = `cmd-jog-${dir}`;
      await answered("cmd-answer", () => pointer(id, "pointerdown"));
      await appliance_seconds(Number(seconds));
      pointer(id, "pointerup");
      await appliance_seconds(0.5);  // the release's write has gone out
    },
  };

  async function run() {
    const panel = $("command");
    // The page's first status and record table: the panel shows (or not) once the status arrived.
    await until("the first status", () => $("sb-word").textContent.startsWith("0x"));
    await until("the record table", () => $("record-table").tBodies[0].rows.length === 32);
    report("panel", panel.hidden || panel.offsetParent === null ? "hidden" : "shown");
    const list = decodeURIComponent(location.hash.slice(1)).split(";").filter((s) => s);
    for (const step of list) {
      const [name, args = ""] = step.split(/=(.*)/s);
      if (!steps[name]) throw new Error(`unknown step '${name}'`);
      await steps[name](args);
    }
  }
  window.addEventListener("load", () => {
    run().then(() => report("probe", "done"), (e) => report("probe", `error: ${e.message}`))
      .finally(() => {
        report("answers", answers.join(" | "));
        // The page's polls end here (their next timer is never set), so Chromium's virtual time
        // runs out at once and the DOM is dumped as reported, without waiting out the budget.
        window.setTimeout = () => 0;
        window.setInterval = () => 0;
      });
  });
})();
