// The "tuning" view (docs/dashboard.md "Tuning"): per axis the stallGuard2 tool (load value AP206
// against velocity, threshold AP174, filter AP173, stall-stop speed AP181, a stall indicator, the
// manual's tuning procedure as steps, and on a virtual module a load applied through its world) and
// the coolStep tool (SEMIN, SEMAX, SEUP, SEDN, SEIMIN as AP172, AP170, AP171, AP169, AP168, the
// threshold speed AP182, actual current AP180 against the load, and the energy it saves).
// Values are sampled by the server's chart sampler (web/sampler.py) while the view is shown.
"use strict";
(() => {
const {api, el, log} = window.OpenTMCL;
const $ = id => document.getElementById(id);
const POLL_MS = 250, KEEP = 400;       // samples fetched 4 times a second; the last 400 (16 s) charted
const CHECK_SECONDS = 5;              // the false-stall check watches this long, unless changed on the page
// coolStep's fields by their TMC chip names, with the TMCM-6212 manual 4.1 / PD86-1180 5 parameters.
const COOLSTEP = [
  {name: "SEMIN", number: 172, meaning: v => v === 0 ? "0: coolStep off" : `lower stallGuard2 threshold ${v * 32} (AP172 × 32): below it the current rises`},
  {name: "SEMAX", number: 170, meaning: (v, all) => `upper threshold ${((all[172] || 0) + v + 1) * 32} ((AP172 + AP170 + 1) × 32): above it the current falls`},
  {name: "SEUP", number: 171, meaning: v => `current up step ${[1, 2, 4, 8][v]} per reading below the lower threshold`},
  {name: "SEDN", number: 169, meaning: v => `current down step after ${[32, 8, 2, 1][v]} reading(s) above the upper threshold`},
  {name: "SEIMIN", number: 168, meaning: (v, all) => `minimum current ${v ? "1/4" : "1/2"} of CS${minimumMa(v, all)}`},
];
// `edits`: coolStep fields chosen on the page but not applied yet (parameter -> value); a read of
// the module's values keeps them, Apply or another axis ends them.
const T = {ctx: null, axis: 0, client: null, series: [], since: 0, timer: null, rows: [], values: {}, params: {}, edits: {},
           stall: false, stallAt: null, check: null, loadInfo: null, busy: false};
window.dashboard.tuning = T;  // for the browser tests and the curious

const units = () => window.OpenTMCL.units;
const has = n => T.params[n] !== undefined;
const ap = n => T.values[n];

function minimumMa(v, all) {
  const u = units(), ma = u && u.currentMa(all[6]);
  return ma ? ` (about ${Math.round(ma / (v ? 4 : 2))} mA of ${Math.round(ma)} mA)` : "";
}

// ---------------------------------------------------------------- markup
function markup(ov) {
  const axes = Array.from({length: ov.axes}, (_, i) => el("option", {value: i}, `${i}`));
  return [
    el("h2", {}, "Tuning: stallGuard2 and coolStep"),
    el("div", {class: "toolbar"},
      el("label", {}, "Axis ", el("select", {id: "tune-axis", onchange: e => selectAxis(Number(e.target.value))}, ...axes)),
      el("span", {class: "ro"}, "load value (AP 206) ", el("b", {id: "tune-sg"}, "-")),
      el("span", {class: "ro"}, "velocity ", el("b", {id: "tune-velocity"}, "-"), " ", el("span", {class: "unit", id: "tune-velocity-unit"}, "")),
      el("span", {id: "tune-stall", class: "lamp stall", title: "stall: the module stopped the axis (AP 207 bit 0, stallGuard error)"}, "no stall"),
      el("button", {id: "tune-stall-clear", onclick: () => setStall(false), title: "forget the stall shown"}, "clear")),
    el("div", {class: "columns tuning"},
      el("div", {class: "tool-panel", id: "sg-panel"},
        el("h3", {}, "stallGuard2"),
        el("div", {class: "motion-row"},
          el("label", {id: "sg-threshold-label"}, "threshold AP 174 ",
            el("button", {id: "sg-threshold-down", onclick: () => nudge(-1), title: "lower: more sensitive"}, "−"),
            el("input", {id: "sg-threshold", type: "number", min: -64, max: 63, step: 1, class: "small"}),
            el("button", {id: "sg-threshold-up", onclick: () => nudge(1), title: "higher: less sensitive"}, "+"),
            el("button", {id: "sg-threshold-set", onclick: () => writeAxis(174, Number($("sg-threshold").value))}, "set")),
          el("label", {id: "sg-filter-label"}, el("input", {id: "sg-filter", type: "checkbox",
            onchange: e => writeAxis(173, e.target.checked ? 1 : 0)}), " filter AP 173"),
          el("label", {id: "sg-stop-label"}, "stop on stall from AP 181 ",
            el("input", {id: "sg-stop-speed", type: "number", step: "any", class: "small"}), " ",
            el("span", {class: "unit", id: "sg-stop-unit"}, ""),
            el("button", {id: "sg-stop-set", onclick: () => writeVelocity(181, Number($("sg-stop-speed").value))}, "set"))),
        el("p", {class: "hint", id: "sg-meanings"}, ""),
        el("canvas", {id: "sg-chart", class: "xy", "aria-label": "load value against velocity"}),
        el("ol", {class: "steps", id: "sg-steps"},
          el("li", {}, el("b", {}, "Run at the working speed. "),
            el("input", {id: "sg-work-speed", type: "number", step: "any", class: "small"}), " ",
            el("span", {class: "unit", id: "sg-work-unit"}, ""), " ",
            el("button", {id: "sg-run", onclick: () => run()}, "Run (ROR)"),
            el("button", {id: "sg-stop", class: "mst", onclick: () => stop()}, "Stop (MST)")),
          el("li", {id: "sg-step-load"}, el("b", {}, "Load the motor as at a stall, "),
            "then lower the threshold until the load value reads 0; with the load removed it must stay well above 0 ",
            "(manual 1.1: at maximum motor load the value reaches zero; a lower AP 174 is more sensitive).",
            el("div", {id: "sg-load-box"})),
          el("li", {}, el("b", {}, "Stop on stall: "), "set AP 181 below the working speed, so that the module stops the axis when the value reaches 0 there. ",
            el("button", {id: "sg-stop-half", onclick: () => useHalfSpeed()}, "AP 181 = half the working speed")),
          el("li", {}, el("b", {}, "Check for false stalls: "), "without the load, start from standstill and run at the working speed; no stall may appear. ",
            el("button", {id: "sg-check", onclick: () => falseStallCheck()}, "Check"), " for ",
            el("input", {id: "sg-check-seconds", type: "number", min: 1, max: 600, step: 1, value: CHECK_SECONDS, class: "small"}), " s",
            " ", el("span", {id: "sg-check-result"}, "")))),
      el("div", {class: "tool-panel", id: "cs-panel"},
        el("h3", {}, "coolStep"),
        el("table", {class: "params", id: "cs-table"}),
        el("div", {class: "motion-row"},
          el("label", {}, "threshold speed AP 182 ", el("input", {id: "cs-speed", type: "number", step: "any", class: "small"}), " ",
            el("span", {class: "unit", id: "cs-speed-unit"}, "")),
          el("span", {id: "cs-slow-box"}),
          el("button", {id: "cs-apply", class: "primary", onclick: () => applyCoolStep()}, "Apply coolStep settings")),
        el("p", {class: "hint"}, "coolStep runs above the threshold speed with SEMIN > 0: it lowers the current while the load value is high ",
          "and raises it again when the load value falls (TMCM-6212 manual 1.2, 6.4)."),
        el("canvas", {id: "cs-chart", class: "xy", "aria-label": "actual current against load value"}),
        el("p", {id: "cs-energy"}, "energy: run the motor above the threshold speed to measure"))),
  ];
}

// ---------------------------------------------------------------- values of the axis
const READ = [2, 3, 4, 6, 7, 168, 169, 170, 171, 172, 173, 174, 181, 182, 183, 206];

async function readValues() {
  const axis = T.axis;
  const numbers = READ.filter(has);
  const r = await api("api/setup/read", {values: numbers.map(number => ({kind: "axis", index: axis, number}))});
  if (axis !== T.axis) return;
  for (const v of r.values) T.values[v.number] = v.value;
  Object.assign(T.values, T.edits);  // what the user chose and has not applied yet stays on the page
  showSettings();
}

function showSettings() {
  const u = units(), a = T.axis;
  const vel = raw => u && u.info ? u.fmt(u.velocity(a, raw), 5) : raw;
  if (document.activeElement !== $("sg-threshold")) $("sg-threshold").value = ap(174) ?? "";
  $("sg-filter").checked = ap(173) === 1;
  if (document.activeElement !== $("sg-stop-speed")) $("sg-stop-speed").value = ap(181) === undefined ? "" : vel(ap(181));
  if (document.activeElement !== $("cs-speed")) $("cs-speed").value = ap(182) === undefined ? "" : vel(ap(182));
  const vu = u && u.info ? u.velocityUnit(a) : "";
  for (const id of ["sg-stop-unit", "sg-work-unit", "cs-speed-unit", "tune-velocity-unit"]) $(id).textContent = vu;
  if (!$("sg-work-speed").value && ap(4) !== undefined) $("sg-work-speed").value = vel(T.values[4] || 0);
  const d = n => (T.params[n] || {}).description || "";
  $("sg-meanings").textContent = `AP 174: ${d(174)} AP 173: ${d(173)} AP 181: ${d(181)}`;
  $("sg-threshold-label").title = d(174); $("sg-filter-label").title = d(173); $("sg-stop-label").title = d(181);
  coolStepTable();
}

function coolStepTable() {
  const rows = [el("tr", {}, ...["", "parameter", "value", "meaning (manual)"].map(h => el("th", {}, h)))];
  for (const f of COOLSTEP) {
    if (!has(f.number)) continue;
    const p = T.params[f.number], v = ap(f.number);
    const input = el("select", {id: `cs-${f.name.toLowerCase()}`, "data-number": f.number},
      ...Array.from({length: p.max - p.min + 1}, (_, k) => el("option", {value: p.min + k}, `${p.min + k}`)));
    if (v !== undefined && v !== null) input.value = String(v);
    input.addEventListener("change", () => {
      T.values[f.number] = T.edits[f.number] = Number(input.value);
      $(`cs-${f.name.toLowerCase()}-meaning`).textContent = f.meaning(Number(input.value), T.values);
    });
    rows.push(el("tr", {}, el("td", {}, el("b", {}, f.name)), el("td", {title: p.description}, `AP ${f.number} ${p.title}`),
      el("td", {}, input), el("td", {id: `cs-${f.name.toLowerCase()}-meaning`, class: "hint"},
        v === undefined || v === null ? "" : f.meaning(v, T.values))));
  }
  $("cs-table").replaceChildren(...rows);
  const slow = $("cs-slow-box");
  if (has(183)) {
    const u = units(), ma = u && u.currentMa(ap(183));
    slow.replaceChildren(el("label", {title: T.params[183].description}, "slow-run current AP 183 ",
      el("input", {id: "cs-slow", type: "number", class: "small", value: ap(183) ?? ""}), ma === null || ma === undefined ? "" : ` (${Math.round(ma)} mA)`));
  } else slow.replaceChildren();
}

// ---------------------------------------------------------------- writes
async function writeAxis(number, value) {
  const axis = T.axis;
  if (!Number.isInteger(value)) { log(`AP ${number}: "${value}" is not a whole number`, "err"); return null; }
  log(`> SAP ${number}, ${axis}, ${value}`, "req");
  try {
    const r = await api("api/params/axis", {axis, number, value, module: T.ctx.overview.address});
    log(`  ${T.params[number].name} = ${r.value}`, "ok");
    T.values[number] = r.value;
    showSettings();
    return r.value;
  } catch (e) { log(`  ${e.message}`, "err"); return null; }
}

function rawVelocity(value) {
  const u = units();
  return u && u.info ? u.velocityRaw(T.axis, value) : Math.round(value);
}

async function writeVelocity(number, value) {
  if (!Number.isFinite(value)) { log(`AP ${number}: "${value}" is not a number`, "err"); return null; }
  return writeAxis(number, rawVelocity(value));
}

function nudge(step) {
  const v = Number($("sg-threshold").value || ap(174) || 0) + step;
  $("sg-threshold").value = Math.max(-64, Math.min(63, v));
  writeAxis(174, Number($("sg-threshold").value));
}

function workSpeed() {
  const v = Number($("sg-work-speed").value);
  if (!Number.isFinite(v) || v <= 0) { log("give the working speed first (step 1)", "err"); return null; }
  return rawVelocity(v);
}

async function run() {
  const raw = workSpeed();
  if (raw !== null) await OpenTMCL.send(`ROR ${T.axis}, ${raw}`);
}

async function stop() { await OpenTMCL.send(`MST ${T.axis}`); }

async function useHalfSpeed() {
  const raw = workSpeed();
  if (raw !== null) await writeAxis(181, Math.max(1, Math.round(raw / 2)));
}

async function falseStallCheck() {
  const raw = workSpeed();
  if (raw === null) return;
  setStall(false);
  const out = $("sg-check-result");
  out.className = ""; out.textContent = "checking…";
  const seconds = Math.max(1, Math.min(600, Number($("sg-check-seconds").value) || CHECK_SECONDS));
  await OpenTMCL.send(`MST ${T.axis}`);   // from standstill; a stall flag of before is read (and cleared) meanwhile
  await new Promise(resolve => setTimeout(resolve, 3 * POLL_MS));
  T.check = {until: Infinity, axis: T.axis, seq: T.since, stalled: false};
  await OpenTMCL.send(`ROR ${T.axis}, ${raw}`);
  T.check.until = performance.now() + seconds * 1000;
  await new Promise(resolve => {
    const tick = () => {
      if (!T.check || T.check.stalled || performance.now() > T.check.until) { resolve(); return; }
      setTimeout(tick, 100);
    };
    tick();
  });
  const stalled = T.check ? T.check.stalled : false;
  T.check = null;
  await OpenTMCL.send(`MST ${T.axis}`);
  out.className = stalled ? "err" : "ok";
  out.textContent = stalled ? "false stall: raise the threshold (AP 174) by one and check again"
                            : `no stall in ${seconds} s at the working speed`;
  log(`stallGuard2 check on axis ${T.axis}: ${out.textContent}`, stalled ? "err" : "ok");
}

async function applyCoolStep() {
  const writes = [];
  for (const f of COOLSTEP) {
    const node = $(`cs-${f.name.toLowerCase()}`);
    if (node) writes.push({kind: "axis", index: T.axis, number: f.number, value: Number(node.value)});
  }
  const speed = Number($("cs-speed").value);
  if (has(182) && Number.isFinite(speed)) writes.push({kind: "axis", index: T.axis, number: 182, value: rawVelocity(speed)});
  const slow = $("cs-slow");
  if (slow && slow.value !== "") writes.push({kind: "axis", index: T.axis, number: 183, value: Number(slow.value)});
  for (const w of writes) log(`> SAP ${w.number}, ${w.index}, ${w.value}`, "req");
  try {
    const r = await api("api/setup/apply", {writes, module: T.ctx.overview.address});
    log(`  coolStep settings applied (${r.sent.length} SAP)`, "ok");
    T.edits = {};
    T.energy = [];
    await readValues();
  } catch (e) { log(`  ${e.message}`, "err"); }
}

// ---------------------------------------------------------------- the load of a virtual module
async function loadBox() {
  const box = $("sg-load-box");
  const ov = T.ctx.overview;
  if (!ov.virtual) {
    box.replaceChildren(el("p", {class: "hint", id: "sg-load-real"},
      "A module on a link: load the motor mechanically (the load your machine must stop at)."));
    return;
  }
  let info = {load: null};
  try { info = await api(`api/world/load/${T.axis}`); } catch (e) { log(e.message, "err"); }
  T.loadInfo = info;
  const input = el("input", {id: "sg-load", type: "number", min: 0, max: 10, step: 0.05, class: "small",
                             value: info.load ?? 0, title: "torque as a fraction of the torque at 100 % current (docs/world.md)"});
  box.replaceChildren(el("div", {class: "motion-row"}, "virtual module: load ", input, " of the full-current torque ",
    el("button", {id: "sg-load-apply", onclick: () => setLoad(Number(input.value))}, "Apply load"),
    el("button", {id: "sg-load-remove", onclick: () => setLoad(null)}, "Remove load"),
    el("span", {class: "hint", id: "sg-load-now"}, info.load === null ? "" : `load now ${info.load}`)));
}

async function setLoad(load) {
  log(load === null ? `> world: axis ${T.axis} load back to the scenario's (virtual module)`
                    : `> world: axis ${T.axis} load ${load} of the full-current torque (virtual module)`, "req");
  try {
    const r = await api("api/world/load", {axis: T.axis, load});
    $("sg-load-now").textContent = `load now ${r.load}`;
    log(`  load now ${r.load}`, "ok");
  } catch (e) { log(`  ${e.message}`, "err"); }
}

// ---------------------------------------------------------------- live samples
function stallNumber() { return has(207) ? 207 : has(208) ? 208 : null; }

async function subscribe(active) {
  const n = T.axis, flag = stallNumber();
  const numbers = active ? [206, 3, 180, 6, ...(flag ? [flag] : [])].filter(has) : [];
  T.series = numbers;
  try {
    const r = await api("api/charts/subscribe", {client: T.client,
      series: numbers.map(number => ({kind: "axis", index: n, number}))});
    T.client = r.client;
  } catch (e) { log(`tuning: ${e.message}`, "err"); }
}

function setStall(on) {
  T.stall = on;
  const lamp = $("tune-stall");
  lamp.classList.toggle("on", on);
  lamp.textContent = on ? "STALL" : "no stall";
  lamp.setAttribute("aria-label", `stall indicator: ${on ? "stall" : "no stall"}`);
}

async function poll() {
  if (!T.client || T.busy) return;
  T.busy = true;
  try {
    const r = await api(`api/charts/samples?client=${encodeURIComponent(T.client)}&since=${T.since}`);
    const col = new Map(r.series.map((k, i) => [Number(k.split(":")[2]), i + 2]));
    const axisOk = r.series.every(k => Number(k.split(":")[1]) === T.axis);
    for (const row of r.rows) {
      T.since = Math.max(T.since, row[0]);
      if (!axisOk) continue;
      const get = n => (col.has(n) ? row[col.get(n)] : null);
      const sample = {t: row[1], sg: get(206), v: get(3), cs: get(180), run: get(6), flag: get(207) ?? get(208)};
      T.rows.push(sample);
      const flagBit = stallNumber() === 207 ? sample.flag & 1 : (sample.flag & 1) && sample.v;
      if (flagBit) {
        setStall(true);
        if (T.check && row[0] > T.check.seq) T.check.stalled = true;
      }
    }
    if (T.rows.length > KEEP) T.rows.splice(0, T.rows.length - KEEP);
    draw();
  } catch (e) {
    if (/subscribe again/.test(e.message)) { T.client = null; await subscribe(true); }
  } finally { T.busy = false; }
}

function draw() {
  const u = units(), a = T.axis, last = T.rows[T.rows.length - 1];
  const vel = raw => (u && u.info ? u.velocity(a, raw) : raw);
  if (last) {
    $("tune-sg").textContent = last.sg ?? "n/a";
    $("tune-velocity").textContent = last.v === null ? "n/a" : u && u.info ? u.fmt(vel(last.v), 5) : last.v;
  }
  const pts = T.rows.filter(s => s.sg !== null && s.v !== null).map(s => ({x: Math.abs(vel(s.v)), y: s.sg}));
  const lines = [{y: 0, label: "stall: load value 0", color: "#c62828"}];
  if (ap(181)) lines.push({x: vel(ap(181)), label: "AP 181: stop on stall above", color: "#ef6c00"});
  const work = Number($("sg-work-speed").value);
  T.sgChart.set(pts, {lines, xMax: Math.max(1, Number.isFinite(work) ? work : 1),
                      xLabel: `|velocity| [${u && u.info ? u.velocityUnit(a) : "raw"}]`});
  // coolStep: actual current (AP 180, in mA where the module has a scale) against the load value
  const scale = u && u.currentScale();
  const ma = n => (scale ? u.scaleMa(n) : n + 1);
  const cpts = T.rows.filter(s => s.cs !== null && s.sg !== null).map(s => ({x: s.sg, y: ma(s.cs)}));
  const top = scale ? scale.rms_ma : 32;
  const runLine = last && last.run !== null ? [{y: scale ? u.currentMa(last.run) : (last.run >> 3) + 1, label: "run current (AP 6)", color: "#2e7d32"}] : [];
  T.csChart.set(cpts, {lines: runLine, xMax: 1023, yMax: top, yLabel: scale ? "actual current [mA]" : "actual current [n+1 of 32]"});
  energy(scale, ma);
}

// coolStep's saving: the coil losses go with the square of the current, so over the samples taken
// while the motor turns, 1 - mean(I_actual^2) / I_run^2 (I_run: AP6's current without coolStep).
function energy(scale, ma) {
  const u = units();
  const moving = T.rows.filter(s => s.v && s.cs !== null && s.run !== null);
  const out = $("cs-energy");
  if (moving.length < 5) { out.textContent = "energy: run the motor above the threshold speed to measure"; T.saving = null; return; }
  const run = s => (scale ? u.currentMa(s.run) : (s.run >> 3) + 1);
  const mean = moving.reduce((acc, s) => acc + ma(s.cs), 0) / moving.length;
  const runMean = moving.reduce((acc, s) => acc + run(s), 0) / moving.length;
  const sq = moving.reduce((acc, s) => acc + ma(s.cs) ** 2, 0) / moving.reduce((acc, s) => acc + run(s) ** 2, 0);
  T.saving = 1 - sq;
  const unit = scale ? " mA" : "/32";
  out.textContent = `energy: average current ${Math.round(mean)}${unit} of ${Math.round(runMean)}${unit} run current over ` +
    `${moving.length} samples while turning; coil losses (∝ I²) ${Math.round(T.saving * 100)} % lower`;
}

// ---------------------------------------------------------------- axis and view
async function selectAxis(axis) {
  T.axis = axis; T.rows = []; T.values = {}; T.edits = {};
  setStall(false);
  $("sg-check-result").textContent = "";
  try {
    const r = await api(`api/params/axis/${axis}`);  // names, ranges and the manual's descriptions
    T.params = Object.fromEntries(r.params.map(p => [p.number, p]));
  } catch (e) { log(e.message, "err"); return; }
  $("sg-work-speed").value = "";
  await readValues();
  await loadBox();
  if (T.ctx.isVisible()) await subscribe(true);
}

OpenTMCL.registerView("tuning", {
  mount(root, ctx) {
    T.ctx = ctx;
    if (!ctx.overview) return;
    root.replaceChildren(...markup(ctx.overview));
    T.sgChart = OpenTMCL.xyChart($("sg-chart"), {xLabel: "|velocity|", yLabel: "load value (AP 206)", yMin: 0, yMax: 1023});
    T.csChart = OpenTMCL.xyChart($("cs-chart"), {xLabel: "load value (AP 206)", yLabel: "actual current", yMin: 0, yMax: 1});
    const u = units();
    if (u) u.onChange(() => { if (T.params[174]) showSettings(); });
  },
  show() {
    if (!T.timer) T.timer = setInterval(poll, POLL_MS);
    (T.params[206] ? readValues().then(() => subscribe(true)) : selectAxis(T.axis)).catch(e => log(`tuning: ${e.message}`, "err"));
  },
  hide() {
    clearInterval(T.timer); T.timer = null;
    subscribe(false);  // nothing sampled (AP 207 is cleared by reading it) while the view is hidden
  },
});
})();
