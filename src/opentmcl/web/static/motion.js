// The "motion" view: per axis rotate left/right with a velocity, stop, move absolute/relative and
// the reference search (docs/dashboard.md "Motion"). Every command goes through the console, so the
// console log shows the TMCL instruction sent (and its reply) for the user to learn from.
// Velocities and positions are in the axis's units (static/units.js, chosen here per axis); the
// jog slider is logarithmic, so slow speeds and full speed are both within reach.
"use strict";
(() => {
const {api, el, log} = window.OpenTMCL;
const $ = id => document.getElementById(id);
const M = {axes: 0, timer: null, info: {}, busy: false, raw: {}, shownAs: {}};

const UNIT_TEXT = {pps: "pps", internal: "internal units"};
const SLIDER = 1000;   // slider steps: 0 is standstill, 1..1000 spread logarithmically from 1 to the maximum

function clamp(v, lo, hi) { return Math.max(lo, Math.min(hi, v)); }
const U = () => window.OpenTMCL.units;
const physical = () => U() && U().info;

// The jog slider: position s (1..SLIDER) -> max^(s/SLIDER) module units (0 at s = 0), and back.
function fromSlider(s, max) { return s <= 0 || max < 1 ? 0 : Math.round(Math.exp(Math.log(max) * s / SLIDER)); }
function toSlider(v, max) { return v < 1 || max < 1 ? 0 : clamp(Math.round(Math.log(v) / Math.log(max) * SLIDER), 1, SLIDER); }

// The velocity field shows the axis's unit; M.raw[i] is the module value it stands for.
function showVelocity(i, raw) {
  M.raw[i] = raw;
  M.shownAs[i] = shownAs(i);
  const u = U();
  $(`motion-${i}-velocity`).value = physical() ? u.fmt(u.velocity(i, raw), 6) : raw;
  const internal = M.info[i] && M.info[i].unit === "internal";
  $(`motion-${i}-velocity-raw`).textContent = !physical() ? "" : internal ? `= ${raw} internal units`
    : u.setting(i).kind !== "pps" ? `= ${raw} pps` : "";
}

function velocity(i, quiet = false) {
  const info = M.info[i] || {velocity_min: 0, velocity_max: 0};
  const text = $(`motion-${i}-velocity`).value.trim();
  const x = Number(text);
  const v = text === "" || !Number.isFinite(x) ? NaN : physical() ? U().velocityRaw(i, x) : x;
  if (!Number.isInteger(v) || v < info.velocity_min || v > info.velocity_max) {
    const whole = !physical() || U().setting(i).kind === "pps" && info.unit === "pps" ? "a whole number " : "";
    const top = physical() ? `${U().fmt(U().velocity(i, info.velocity_max), 6)} ${U().velocityUnit(i)}` : info.velocity_max;
    if (!quiet) log(`axis ${i}: velocity must be ${whole}0…${top}, not "${text}"`, "err");
    return null;
  }
  return v;
}

function target(i) {
  const text = $(`motion-${i}-target`).value.trim();
  const x = Number(text);
  const v = text === "" || !Number.isFinite(x) ? NaN : physical() ? U().positionRaw(i, x) : x;
  if (!Number.isInteger(v) || v < -2147483648 || v > 2147483647) {
    log(`axis ${i}: the target must be a position of -2147483648…2147483647 microsteps, not "${text}"`, "err");
    return null;
  }
  return v;
}

async function send(line) {
  await OpenTMCL.send(line);
  refresh();
}

function tools(i, ov) {
  const vel = el("input", {type: "number", id: `motion-${i}-velocity`, step: "any", class: "velocity"});
  const slider = el("input", {type: "range", id: `motion-${i}-slider`, class: "slider", min: 0, max: SLIDER, step: 1,
                              title: "velocity (logarithmic: slow speeds on the left, full speed at the right end)",
                              "aria-label": `axis ${i} velocity`});
  vel.addEventListener("input", () => {
    const v = velocity(i, true);
    if (v !== null) { M.raw[i] = v; slider.value = toSlider(v, (M.info[i] || {}).velocity_max || 0); }
  });
  slider.addEventListener("input", () => showVelocity(i, fromSlider(Number(slider.value), (M.info[i] || {}).velocity_max || 0)));
  const withVelocity = mnemonic => () => { const v = velocity(i); if (v !== null) send(`${mnemonic} ${i}, ${v}`); };
  const withTarget = mode => () => { const t = target(i); if (t !== null) send(`MVP ${mode}, ${i}, ${t}`); };
  const ro = (key, label) => el("span", {class: "ro"}, el("span", {}, label), el("b", {id: `motion-${i}-${key}`}, "-"));
  return el("div", {class: "motion-axis", id: `motion-${i}`},
    el("h3", {}, `Axis ${i}`),
    el("div", {class: "motion-row"},
      el("button", {id: `motion-${i}-rol`, title: `ROL ${i}, <velocity> (rotate left)`, onclick: withVelocity("ROL")}, "◀ ROL"),
      el("button", {id: `motion-${i}-mst`, class: "mst", title: `MST ${i} (motor stop)`, onclick: () => send(`MST ${i}`)}, "■ MST"),
      el("button", {id: `motion-${i}-ror`, title: `ROR ${i}, <velocity> (rotate right)`, onclick: withVelocity("ROR")}, "ROR ▶"),
      el("label", {}, "velocity ", vel, " ", el("span", {id: `motion-${i}-unit`, class: "unit"}, ov.velocity_unit),
         " ", el("span", {id: `motion-${i}-velocity-raw`, class: "unit"}, "")),
      slider),
    el("div", {class: "motion-row"},
      el("label", {}, "target ", el("input", {type: "number", id: `motion-${i}-target`, value: 0, step: "any", class: "target"}),
         " ", el("span", {id: `motion-${i}-target-unit`, class: "unit"}, "µsteps")),
      el("button", {id: `motion-${i}-abs`, title: `MVP ABS, ${i}, <target>`, onclick: withTarget("ABS")}, "MVP ABS"),
      el("button", {id: `motion-${i}-rel`, title: `MVP REL, ${i}, <target>`, onclick: withTarget("REL")}, "MVP REL"),
      el("span", {class: "sep"}),
      el("button", {id: `motion-${i}-rfs-start`, title: `RFS START, ${i}`, onclick: () => send(`RFS START, ${i}`)}, "RFS START"),
      el("button", {id: `motion-${i}-rfs-stop`, title: `RFS STOP, ${i}`, onclick: () => send(`RFS STOP, ${i}`)}, "RFS STOP"),
      el("span", {class: "ro"}, el("span", {}, "reference search"), el("b", {id: `motion-${i}-rfs`}, "-"))),
    el("div", {class: "motion-row readout"},
      ro("position", "position"), ro("target_position", "target"), ro("actual_speed", "actual speed"),
      el("span", {id: `motion-${i}-units`, class: "units-box"})));
}

// What the velocity field's text depends on besides the value: it is written again only when this
// changes (or the units were chosen anew), so a poll never overwrites what the user is typing.
function shownAs(i) { return `${physical() ? "physical" : "module"} ${(M.info[i] || {}).unit}`; }

function unitTexts(i, chosen = false) {
  const info = M.info[i];
  if (!info) return;
  const u = U(), unit = $(`motion-${i}-unit`);
  unit.textContent = physical() ? u.velocityUnit(i) : UNIT_TEXT[info.unit] || info.unit;
  unit.title = physical() ? `${u.describe(i)}; the module takes ${UNIT_TEXT[info.unit] || info.unit}` :
    info.unit === "internal" ? "internal units of the motion controller (AP255 = 0, or a TMC429 module)" : "microsteps per second (AP255 = 1)";
  $(`motion-${i}-target-unit`).textContent = physical() ? u.positionUnit(i) : "µsteps";
  if (M.raw[i] !== undefined && (chosen || M.shownAs[i] !== shownAs(i))) showVelocity(i, M.raw[i]);
}

function showInfo(i, info) {
  const first = !M.info[i];
  M.info[i] = info;
  const known = physical() && U().axis(i);
  if (known && known.velocity_unit !== info.unit && !M.reloading) {  // AP255 changed: new factors
    M.reloading = true;
    U().reload().catch(e => log(e.message, "err")).finally(() => { M.reloading = false; });
  }
  const slider = $(`motion-${i}-slider`);
  if (first) {
    const start = clamp(info.max_positioning_speed ?? Math.round(info.velocity_max / 10), info.velocity_min, info.velocity_max);
    showVelocity(i, start);
    slider.value = toSlider(start, info.velocity_max);
    $(`motion-${i}-units`).replaceChildren(U() ? U().chooser(i) : "");
  }
  unitTexts(i);
  const u = U(), pos = v => (physical() && v !== null && v !== undefined ? `${u.fmt(u.position(i, v), 6)} ${u.positionUnit(i)}` : v);
  $(`motion-${i}-position`).textContent = pos(info.position) ?? "n/a";
  $(`motion-${i}-target_position`).textContent = pos(info.target_position) ?? "n/a";
  $(`motion-${i}-actual_speed`).textContent = physical() && info.actual_speed !== null ?
    `${u.fmt(u.velocity(i, info.actual_speed), 6)} ${u.velocityUnit(i)}` : info.actual_speed ?? "n/a";
  const rfs = $(`motion-${i}-rfs`);
  rfs.textContent = info.rfs_status === null ? "n/a" : info.rfs_status === 0 ? "not active" : `active (${info.rfs_status})`;
  rfs.className = info.rfs_status ? "active" : "";
}

async function refresh() {
  if (M.busy) return;  // the previous round is still under way
  M.busy = true;
  try {
    for (let i = 0; i < M.axes; i++) showInfo(i, await api(`api/motion/${i}`));
  } catch (e) { log(e.message, "err"); }
  finally { M.busy = false; }
}

OpenTMCL.registerView("motion", {
  mount(root, ctx) {
    const ov = ctx.overview;
    M.axes = ov ? ov.axes : 0;
    root.replaceChildren(el("h2", {}, "Motion"),
      el("p", {class: "hint"}, "Each button sends the TMCL command shown on hover; the console logs it with the reply."),
      ...Array.from({length: M.axes}, (_, i) => tools(i, ov)));
  },
  show() {
    refresh(); M.timer = setInterval(refresh, 500);
    if (U() && !M.subscribed) { M.subscribed = true; U().onChange(() => { for (let i = 0; i < M.axes; i++) unitTexts(i, true); }); }
  },
  hide() { clearInterval(M.timer); M.timer = null; },
});
})();
