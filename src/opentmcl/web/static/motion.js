// The "motion" view: per axis rotate left/right with a velocity, stop, move absolute/relative and
// the reference search (docs/dashboard.md "Motion"). Every command goes through the console, so the
// console log shows the TMCL instruction sent (and its reply) for the user to learn from.
"use strict";
(() => {
const {api, el, log} = window.OpenTMCL;
const $ = id => document.getElementById(id);
const M = {axes: 0, timer: null, info: {}, busy: false};

const UNIT_TEXT = {pps: "pps", internal: "internal units"};

function clamp(v, lo, hi) { return Math.max(lo, Math.min(hi, v)); }

function velocity(i) {
  const info = M.info[i] || {velocity_min: 0, velocity_max: 0};
  const raw = $(`motion-${i}-velocity`).value.trim();
  const v = Number(raw);
  if (raw === "" || !Number.isInteger(v) || v < info.velocity_min || v > info.velocity_max) {
    log(`axis ${i}: velocity must be a whole number ${info.velocity_min}…${info.velocity_max}, not "${raw}"`, "err");
    return null;
  }
  return v;
}

function target(i) {
  const raw = $(`motion-${i}-target`).value.trim();
  const v = Number(raw);
  if (raw === "" || !Number.isInteger(v) || v < -2147483648 || v > 2147483647) {
    log(`axis ${i}: the target must be a whole number of microsteps, not "${raw}"`, "err");
    return null;
  }
  return v;
}

async function send(line) {
  await OpenTMCL.send(line);
  refresh();
}

function tools(i, ov) {
  const vel = el("input", {type: "number", id: `motion-${i}-velocity`, step: 1, class: "velocity"});
  const slider = el("input", {type: "range", id: `motion-${i}-slider`, class: "slider",
                              title: "velocity", "aria-label": `axis ${i} velocity`});
  vel.addEventListener("input", () => { slider.value = vel.value; });
  slider.addEventListener("input", () => { vel.value = slider.value; });
  const withVelocity = mnemonic => () => { const v = velocity(i); if (v !== null) send(`${mnemonic} ${i}, ${v}`); };
  const withTarget = mode => () => { const t = target(i); if (t !== null) send(`MVP ${mode}, ${i}, ${t}`); };
  const ro = (key, label) => el("span", {class: "ro"}, el("span", {}, label), el("b", {id: `motion-${i}-${key}`}, "-"));
  return el("div", {class: "motion-axis", id: `motion-${i}`},
    el("h3", {}, `Axis ${i}`),
    el("div", {class: "motion-row"},
      el("button", {id: `motion-${i}-rol`, title: `ROL ${i}, <velocity> (rotate left)`, onclick: withVelocity("ROL")}, "◀ ROL"),
      el("button", {id: `motion-${i}-mst`, class: "mst", title: `MST ${i} (motor stop)`, onclick: () => send(`MST ${i}`)}, "■ MST"),
      el("button", {id: `motion-${i}-ror`, title: `ROR ${i}, <velocity> (rotate right)`, onclick: withVelocity("ROR")}, "ROR ▶"),
      el("label", {}, "velocity ", vel, " ", el("span", {id: `motion-${i}-unit`, class: "unit"}, ov.velocity_unit)),
      slider),
    el("div", {class: "motion-row"},
      el("label", {}, "target ", el("input", {type: "number", id: `motion-${i}-target`, value: 0, step: 1, class: "target"}),
         " µsteps"),
      el("button", {id: `motion-${i}-abs`, title: `MVP ABS, ${i}, <target>`, onclick: withTarget("ABS")}, "MVP ABS"),
      el("button", {id: `motion-${i}-rel`, title: `MVP REL, ${i}, <target>`, onclick: withTarget("REL")}, "MVP REL"),
      el("span", {class: "sep"}),
      el("button", {id: `motion-${i}-rfs-start`, title: `RFS START, ${i}`, onclick: () => send(`RFS START, ${i}`)}, "RFS START"),
      el("button", {id: `motion-${i}-rfs-stop`, title: `RFS STOP, ${i}`, onclick: () => send(`RFS STOP, ${i}`)}, "RFS STOP"),
      el("span", {class: "ro"}, el("span", {}, "reference search"), el("b", {id: `motion-${i}-rfs`}, "-"))),
    el("div", {class: "motion-row readout"},
      ro("position", "position"), ro("target_position", "target"), ro("actual_speed", "actual speed")));
}

function showInfo(i, info) {
  const first = !M.info[i];
  M.info[i] = info;
  $(`motion-${i}-unit`).textContent = UNIT_TEXT[info.unit] || info.unit;
  $(`motion-${i}-unit`).title = info.unit === "internal" ?
    "internal units of the motion controller (AP255 = 0, or a TMC429 module)" : "microsteps per second (AP255 = 1)";
  const vel = $(`motion-${i}-velocity`), slider = $(`motion-${i}-slider`);
  for (const e of [vel, slider]) { e.min = info.velocity_min; e.max = info.velocity_max; }
  if (first) {
    const start = info.max_positioning_speed ?? Math.round(info.velocity_max / 10);
    vel.value = slider.value = clamp(start, info.velocity_min, info.velocity_max);
  }
  for (const k of ["position", "target_position", "actual_speed"]) $(`motion-${i}-${k}`).textContent = info[k] ?? "n/a";
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
  show() { refresh(); M.timer = setInterval(refresh, 500); },
  hide() { clearInterval(M.timer); M.timer = null; },
});
})();
