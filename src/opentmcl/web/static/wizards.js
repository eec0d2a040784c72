// The "set-up" view (docs/dashboard.md "Set-up wizards"): guided set-up of the motor (currents in mA,
// microstep resolution, velocity and acceleration in physical units), the reference search (mode from
// the manual's descriptions, switch polarity, speeds, then run it and watch the switches) and the
// encoder (resolution or prescaler, maximum deviation). Each wizard shows the TMCL commands it will
// send and sends nothing before Apply; Apply writes all or none (web/setup.py); Cancel at any step
// writes back what Apply replaced; Finish keeps the values and, when asked, stores them in the EEPROM
// (STAP/STGP where the module has them).
"use strict";
(() => {
const {api, el, log} = window.OpenTMCL;
const $ = id => document.getElementById(id);
const W = {ctx: null, axis: 0, params: {}, globals: {}, active: null, timer: null};
window.dashboard.wizard = W;  // for the browser tests and the curious

const units = () => window.OpenTMCL.units;
const ov = () => W.ctx.overview;
const axisItem = (number, value) => ({kind: "axis", index: W.axis, number, value});
const fmt = x => units().fmt(x, 5);

function mnemonic(w) { return w.kind === "axis" ? `SAP ${w.number}, ${w.index}, ${w.value}` : `SGP ${w.number}, ${w.index}, ${w.value}`; }
function storeMnemonic(w) { return w.kind === "axis" ? `STAP ${w.number}, ${w.index}` : `STGP ${w.number}, ${w.index}`; }
function canStore(w) {
  const p = w.kind === "axis" ? W.params[w.number] : W.globals[`${w.index}:${w.number}`];
  return p && p.can_store;
}

async function readItems(list) {
  if (!list.length) return {};
  const r = await api("api/setup/read", {values: list.map(({kind, index, number}) => ({kind, index, number}))});
  return Object.fromEntries(r.values.map(v => [`${v.kind}:${v.index}:${v.number}`, v.value]));
}

// ---------------------------------------------------------------- the wizard frame
// A wizard: {id, title, reads: [item], steps: [{title, body(w) -> nodes, check(w) -> error text or ""}],
//            writes(w) -> [item with value], run?: {title, body(w) -> nodes, tick(w)}}
async function open(spec) {
  if (W.active) await cancel();
  const w = {spec, step: 0, values: {}, applied: null, store: false};
  W.active = w;
  try { w.values = await readItems(spec.reads()); } catch (e) { log(`${spec.title}: ${e.message}`, "err"); W.active = null; return; }
  w.start = {...w.values};
  log(`${spec.title} wizard for axis ${W.axis}: nothing is sent before Apply`, "req");
  render();
}

function buttons(...list) { return el("div", {class: "toolbar wizard-buttons"}, ...list); }

function render() {
  clearInterval(W.timer); W.timer = null;  // a step that watches the module starts its own
  const w = W.active, box = $("wizard-panel");
  if (!w) { box.replaceChildren(); box.hidden = true; return; }
  box.hidden = false;
  const steps = w.spec.steps, last = steps.length;   // steps, then review (last), then the applied page
  const names = [...steps.map(s => s.title), "Review", ...(w.spec.run ? [w.spec.run.title] : []), "Finish"];
  const at = w.applied ? last + 1 : w.step;
  const crumbs = el("ol", {class: "wizard-steps"}, ...names.map((n, k) => el("li", {class: k === at ? "active" : k < at ? "done" : ""}, n)));
  const head = [el("h3", {}, `${w.spec.title}: axis ${W.axis}`), crumbs];
  const err = el("div", {class: "wizard-error", id: "wizard-error"});
  const cancelButton = el("button", {id: "wizard-cancel", onclick: () => cancel()},
                          w.applied ? "Cancel (write back the old values)" : "Cancel");
  if (w.applied) {
    const page = w.spec.run ? w.spec.run.body(w) : [];
    const storable = w.applied.writes.filter(canStore);
    const store = el("label", {}, el("input", {type: "checkbox", id: "wizard-store", ...(storable.length ? {} : {disabled: ""}),
                                                onchange: e => { w.store = e.target.checked; }}),
      storable.length ? ` store in the EEPROM at Finish (${storable.map(storeMnemonic).join("; ")})`
                      : ` store in the EEPROM: ${ov().module} has no STAP for these axis parameters (they are volatile)`);
    box.replaceChildren(...head, el("p", {class: "ok", id: "wizard-applied"}, `Applied: ${w.applied.sent.join("; ") || "nothing to change"}`),
      ...page, store, err,
      buttons(el("button", {id: "wizard-finish", class: "primary", onclick: () => finish()}, "Finish"), cancelButton));
    return;
  }
  if (w.step >= last) {  // review
    const writes = changed(w);
    const list = writes.length ? writes.map(x => el("li", {}, el("code", {}, mnemonic(x)), x.label ? ` (${x.label})` : ""))
                               : [el("li", {}, "nothing: every value is already set")];
    box.replaceChildren(...head, el("p", {}, "These TMCL commands will be sent when you press Apply (all or none):"),
      el("ul", {id: "wizard-commands", class: "commands"}, ...list), err,
      buttons(el("button", {id: "wizard-back", onclick: () => { w.step -= 1; render(); }}, "Back"),
              el("button", {id: "wizard-apply", class: "primary", onclick: () => apply()}, "Apply"), cancelButton));
    return;
  }
  const step = steps[w.step];
  box.replaceChildren(...head, el("h4", {}, step.title), ...step.body(w), err,
    buttons(...(w.step ? [el("button", {id: "wizard-back", onclick: () => { w.step -= 1; render(); }}, "Back")] : []),
            el("button", {id: "wizard-next", class: "primary", onclick: () => next()}, "Next"), cancelButton));
}

function next() {
  const w = W.active, problem = w.spec.steps[w.step].check(w);
  if (problem) { $("wizard-error").textContent = problem; return; }
  w.step += 1;
  render();
}

function changed(w) {
  return w.spec.writes(w).filter(x => w.start[`${x.kind}:${x.index}:${x.number}`] !== x.value);
}

async function apply() {
  const w = W.active, writes = changed(w);
  for (const x of writes) log(`> ${mnemonic(x)}`, "req");
  try {
    const r = writes.length ? await api("api/setup/apply", {writes: writes.map(({kind, index, number, value}) => ({kind, index, number, value})),
                                                           module: ov().address}) : {sent: [], old: []};
    w.applied = {writes, sent: r.sent, old: r.old};
    log(`  applied ${r.sent.length} value(s)`, "ok");
    await units().reload();
    render();
  } catch (e) { $("wizard-error").textContent = e.message; log(`  ${e.message} (nothing kept)`, "err"); }
}

async function finish() {
  const w = W.active;
  const storable = w.applied.writes.filter(canStore);
  if (w.store && storable.length) {
    for (const x of storable) log(`> ${storeMnemonic(x)}`, "req");
    try {
      const r = await api("api/setup/apply", {writes: storable.map(({kind, index, number, value}) => ({kind, index, number, value})),
                                              store: true, module: ov().address});
      log(`  stored: ${r.stored.join("; ")}`, "ok");
    } catch (e) { $("wizard-error").textContent = e.message; log(`  ${e.message}`, "err"); return; }
  }
  if (w.spec.finish) await w.spec.finish(w);
  log(`${w.spec.title} wizard finished`, "ok");
  close();
}

async function cancel() {
  const w = W.active;
  if (!w) return;
  if (w.spec.abort) await w.spec.abort(w);
  if (w.applied && w.applied.old.length) {
    const back = w.applied.old;
    for (const x of back) log(`> ${mnemonic(x)}`, "req");
    try {
      await api("api/setup/apply", {writes: back, module: ov().address});
      log(`  ${w.spec.title} cancelled: ${back.length} value(s) written back`, "ok");
      await units().reload();
    } catch (e) { log(`  ${e.message}`, "err"); return; }
  } else log(`${w.spec.title} cancelled: ${w.applied ? "nothing to write back" : "nothing was sent"}`, "ok");
  close();
}

function close() { W.active = null; clearInterval(W.timer); W.timer = null; render(); }

// ---------------------------------------------------------------- input helpers
function field(id, label, value, attrs = {}, after = "") {
  return el("label", {class: "wizard-field"}, label, " ",
    el("input", {id, value: value ?? "", class: "small", ...attrs}), " ", after);
}
const num = id => Number($(id).value);
function inRange(number, value) {
  const p = W.params[number];
  return p && value >= p.min && value <= p.max && !(p.values.length && !p.values.includes(value));
}
function speedError(number, raw, what) {
  const p = W.params[number];
  if (!Number.isInteger(raw) || !inRange(number, raw)) {
    const u = units(), top = u.velocity(W.axis, p.max);
    return `${what}: ${raw} is outside AP ${number}'s range ${p.min}…${p.max} (at most ${fmt(top)} ${u.velocityUnit(W.axis)})`;
  }
  return "";
}

// ---------------------------------------------------------------- motor
const microText = k => (k === 0 ? "fullstep" : k === 1 ? "halfstep" : `${2 ** k} microsteps`);

function motorSpec() {
  const has = n => W.params[n] !== undefined;
  return {
    title: "Motor",
    reads: () => [4, 5, 6, 7, 140, 202].filter(has).map(n => axisItem(n)),
    steps: [
      {title: "Motor and microsteps", body: w => {
        const code = w.m?.code ?? w.values[`axis:${W.axis}:140`];
        const sel = el("select", {id: "wiz-microsteps"}, ...(W.params[140].values.length ? W.params[140].values : [0, 1, 2, 3, 4, 5, 6, 7, 8])
          .map(k => el("option", {value: k}, `${k}: ${microText(k)}`)));
        sel.value = String(code);
        return [
          has(202) ? field("wiz-fullsteps", "full steps per round (AP 202)", w.m?.fullsteps ?? w.values[`axis:${W.axis}:202`], {type: "number", min: 1},
                           "(200 for a 1.8° motor)")
                   : el("p", {class: "hint"}, `full steps per round: 200 (a 1.8° motor; ${ov().module} has no AP 202)`),
          el("label", {class: "wizard-field", title: W.params[140].description}, "microstep resolution (AP 140) ", sel)];
      }, check: w => {
        const fullsteps = has(202) ? num("wiz-fullsteps") : 200, code = Number($("wiz-microsteps").value);
        if (!Number.isInteger(fullsteps) || !inRange(202, fullsteps) && has(202) || fullsteps < 1) return "full steps per round: a whole number from 1";
        w.m = {...(w.m || {}), fullsteps, code};
        return "";
      }},
      {title: "Currents", body: w => {
        const u = units(), sc = u.currentScale();
        const run = w.m.run ?? w.values[`axis:${W.axis}:6`], standby = w.m.standby ?? w.values[`axis:${W.axis}:7`];
        if (!sc) {
          return [el("p", {class: "hint"}, `The ${ov().module} manual gives no current scale: the raw values 0…255 (255 = 100 % of the module's maximum).`),
                  field("wiz-run-raw", "run current AP 6", run, {type: "number", min: 0, max: 255}),
                  field("wiz-standby-raw", "standby current AP 7", standby, {type: "number", min: 0, max: 255})];
        }
        const show = id => { const out = $(`${id}-raw`); if (out) out.textContent = `→ value ${u.currentRaw(num(id))} = ${Math.round(u.currentMa(u.currentRaw(num(id))))} mA RMS`; };
        const runInput = field("wiz-run-ma", "run current", Math.round(u.currentMa(run)), {type: "number", min: 0, step: 1,
          oninput: () => show("wiz-run-ma")}, el("span", {}, "mA RMS ", el("span", {id: "wiz-run-ma-raw", class: "hint"}, `→ value ${run}`)));
        const standbyInput = field("wiz-standby-ma", "standby current", Math.round(u.currentMa(standby)), {type: "number", min: 0, step: 1,
          oninput: () => show("wiz-standby-ma")}, el("span", {}, "mA RMS ", el("span", {id: "wiz-standby-ma-raw", class: "hint"}, `→ value ${standby}`)));
        return [runInput, standbyInput,
          el("p", {class: "hint", id: "wiz-current-scale"}, `Current scale: ${sc.rms_ma} mA RMS (${sc.peak_ma} mA peak) at 255; ` +
            `${sc.steps === 32 ? "32 steps of " + (sc.rms_ma / 32).toFixed(2) + " mA" : "linear"}. Source: ${sc.source}.`)];
      }, check: w => {
        const u = units(), sc = u.currentScale(), a = W.axis;
        // a current left as shown keeps its value (another value of the same step would be a needless SAP)
        const raw = (id, number) => {
          const before = w.values[`axis:${a}:${number}`];
          return before !== undefined && Math.round(u.currentMa(before)) === num(id) ? before : u.currentRaw(num(id));
        };
        const run = sc ? raw("wiz-run-ma", 6) : num("wiz-run-raw");
        const standby = sc ? raw("wiz-standby-ma", 7) : num("wiz-standby-raw");
        if (sc && (num("wiz-run-ma") > sc.rms_ma || num("wiz-standby-ma") > sc.rms_ma)) return `at most ${sc.rms_ma} mA RMS on the ${ov().module}`;
        if (![run, standby].every(v => Number.isInteger(v) && v >= 0 && v <= 255)) return "currents: 0…255";
        if (standby > run) return "the standby current should not exceed the run current (manual: as low as possible)";
        w.m = {...w.m, run, standby};
        return "";
      }},
      {title: "Velocity and acceleration", body: w => {
        const u = units(), a = W.axis, n = w.m.code;
        const perRound = 2 ** n * w.m.fullsteps;
        const v = u.velocity(a, w.values[`axis:${a}:4`]), acc = u.accel(a, w.values[`axis:${a}:5`]);
        return [
          el("p", {}, u.chooser(a, () => render(), "wiz-units")),
          el("p", {class: "hint"}, `${perRound} microsteps per round (${w.m.fullsteps} full steps × ${2 ** n}); ` +
            "pps = rps × full steps × microsteps (TMCM-6212 manual 6.5)"),
          field("wiz-velocity", "maximum positioning speed (AP 4)", w.m.velocity ?? (v === null ? "" : fmt(v)), {type: "number", step: "any", min: 0}, u.velocityUnit(a)),
          field("wiz-accel", "maximum acceleration (AP 5)", w.m.accel ?? (acc === null ? "" : fmt(acc)), {type: "number", step: "any", min: 0}, u.accelUnit(a))];
      }, check: w => {
        const u = units(), a = W.axis, perRound = 2 ** w.m.code * w.m.fullsteps;
        const velocity = num("wiz-velocity"), accel = num("wiz-accel");
        if (!(velocity >= 0) || !(accel >= 0)) return "give the speed and the acceleration";
        // a value left as shown, with the microsteps unchanged, keeps its module value
        const same = w.m.code === w.values[`axis:${a}:140`] && w.m.fullsteps === (w.values[`axis:${a}:202`] ?? w.m.fullsteps);
        const kept = (id, number, conv) => {
          const before = w.values[`axis:${a}:${number}`];
          return same && before !== undefined && fmt(conv(a, before)) === $(id).value.trim() ? before : null;
        };
        const vraw = kept("wiz-velocity", 4, u.velocity) ?? u.velocityRaw(a, velocity, perRound);
        const araw = kept("wiz-accel", 5, u.accel) ?? u.accelRaw(a, accel, perRound);
        const problem = speedError(4, vraw, "speed");
        if (problem) return problem;
        if (!inRange(5, araw)) return `acceleration: ${araw} is outside AP 5's range ${W.params[5].min}…${W.params[5].max}`;
        w.m = {...w.m, velocity, accel, vraw, araw};
        return "";
      }},
    ],
    writes: w => [
      ...(has(202) ? [{...axisItem(202, w.m.fullsteps), label: "full steps per round"}] : []),
      {...axisItem(140, w.m.code), label: microText(w.m.code)},
      {...axisItem(6, w.m.run), label: currentLabel(w.m.run, "run current")},
      {...axisItem(7, w.m.standby), label: currentLabel(w.m.standby, "standby current")},
      {...axisItem(4, w.m.vraw), label: `${w.m.velocity} ${units().velocityUnit(W.axis)}`},
      {...axisItem(5, w.m.araw), label: `${w.m.accel} ${units().accelUnit(W.axis)}`},
    ],
  };
}

function currentLabel(raw, what) {
  const ma = units().currentMa(raw);
  return ma === null ? what : `${what} ${Math.round(ma)} mA RMS`;
}

// ---------------------------------------------------------------- reference search
function modeText(mode) {  // the manual's words for an AP 193 value (web/setup.py reference_modes)
  const m = (ov().reference_modes || []).find(x => x.mode === mode);
  return m ? m.text : `mode ${mode}`;
}

function referenceSpec() {
  const a = W.axis, hasA = n => W.params[n] !== undefined;
  const polarity = hasA(24) ? [24, 25].map(n => axisItem(n)) : W.globals["0:79"] ? [{kind: "global", index: 0, number: 79}] : [];
  const switchItems = [11, 10, 9].filter(hasA).map(n => axisItem(n));
  return {
    title: "Reference search",
    reads: () => [...[193, 194, 195].map(n => axisItem(n)), ...polarity],
    steps: [
      {title: "Mode", body: w => {
        const mode = w.r?.mode ?? w.values[`axis:${a}:193`];
        const values = (ov().reference_modes || []).map(x => x.mode);
        return [el("p", {class: "hint"}, W.params[193].description),
          el("div", {id: "wiz-modes", class: "wizard-choices"}, ...values.map(m => el("label", {},
            el("input", {type: "radio", name: "wiz-mode", value: m, id: `wiz-mode-${m}`, ...(m === mode ? {checked: ""} : {})}),
            ` ${m}: ${modeText(m)}`)))];
      }, check: w => {
        const c = document.querySelector("input[name=wiz-mode]:checked");
        if (!c) return "choose a mode";
        w.r = {...(w.r || {}), mode: Number(c.value)};
        return "";
      }},
      {title: "Switches", body: w => {
        const rows = polarity.map(it => {
          const key = `${it.kind}:${it.index}:${it.number}`, p = it.kind === "axis" ? W.params[it.number] : W.globals[`0:${it.number}`];
          const v = w.r.polarity?.[key] ?? w.values[key];
          return el("label", {class: "wizard-field", title: p.description},
            el("input", {type: "checkbox", id: `wiz-polarity-${it.number}`, ...(v ? {checked: ""} : {})}), ` ${p.title} (${it.kind === "axis" ? "AP" : "GP"} ${it.number}): inverted`);
        });
        W.timer = setInterval(() => watchSwitches(switchItems), 300);
        return [...rows, el("p", {}, "Switches now: ", ...switchLamps()),
          el("p", {class: "hint"}, "Press each switch by hand (or move the axis) and watch its lamp: a lamp that is on while the switch is free needs its polarity inverted.")];
      }, check: w => {
        const pol = {};
        for (const it of polarity) pol[`${it.kind}:${it.index}:${it.number}`] = $(`wiz-polarity-${it.number}`).checked ? 1 : 0;
        w.r = {...w.r, polarity: pol};
        return "";
      }},
      {title: "Speeds", body: w => {
        const u = units();
        return [el("p", {}, u.chooser(a, () => render(), "wiz-units")),
          field("wiz-search-speed", "search speed (AP 194)", w.r.search ?? fmt(u.velocity(a, w.values[`axis:${a}:194`])), {type: "number", step: "any", min: 0}, u.velocityUnit(a)),
          field("wiz-switch-speed", "switch speed (AP 195)", w.r.switch ?? fmt(u.velocity(a, w.values[`axis:${a}:195`])), {type: "number", step: "any", min: 0}, u.velocityUnit(a)),
          el("p", {class: "hint"}, `${W.params[194].description} ${W.params[195].description}`)];
      }, check: w => {
        const u = units(), search = num("wiz-search-speed"), sw = num("wiz-switch-speed");
        const sraw = u.velocityRaw(a, search), wraw = u.velocityRaw(a, sw);
        const problem = speedError(194, sraw, "search speed") || speedError(195, wraw, "switch speed");
        if (problem) return problem;
        if (!(wraw > 0) || !(sraw > 0)) return "both speeds must be above 0";
        if (wraw > sraw) return "the switch speed should be slower than the search speed (manual: AP 195 slower than AP 194)";
        w.r = {...w.r, search, switch: sw, sraw, wraw};
        return "";
      }},
    ],
    writes: w => [
      {...axisItem(193, w.r.mode), label: modeText(w.r.mode)},
      ...polarity.map(it => ({...it, value: w.r.polarity[`${it.kind}:${it.index}:${it.number}`], label: "switch polarity"})),
      {...axisItem(194, w.r.sraw), label: `${w.r.search} ${units().velocityUnit(a)}`},
      {...axisItem(195, w.r.wraw), label: `${w.r.switch} ${units().velocityUnit(a)}`},
    ],
    run: {title: "Run", body: w => {
      W.timer = setInterval(() => watchSearch(w, switchItems), 300);
      return [el("p", {}, "Run the search and watch the switches: ",
          el("button", {id: "wiz-rfs-start", class: "primary", onclick: () => OpenTMCL.send(`RFS START, ${a}`)}, "RFS START"),
          el("button", {id: "wiz-rfs-stop", class: "mst", onclick: () => OpenTMCL.send(`RFS STOP, ${a}`)}, "RFS STOP")),
        el("p", {}, "Switches: ", ...switchLamps()),
        el("p", {}, "search: ", el("b", {id: "wiz-rfs-status"}, "-"), " · position ", el("b", {id: "wiz-rfs-position"}, "-"),
          " · last reference position (AP 197) ", el("b", {id: "wiz-rfs-last"}, "-"))];
    }},
    abort: async w => { if (w.applied && w.searching) await OpenTMCL.send(`RFS STOP, ${a}`); },
  };
}

function switchLamps() {
  return [["left", 11], ["right", 10], ["home", 9]].filter(([, n]) => W.params[n] !== undefined)
    .map(([name, n]) => el("span", {class: "lamp", id: `wiz-switch-${name}`, title: `AP ${n}`}, name));
}

async function watchSwitches(items) {
  if (!W.active || !items.length) return;
  try {
    const v = await readItems(items);
    for (const [name, n] of [["left", 11], ["right", 10], ["home", 9]]) {
      const lamp = $(`wiz-switch-${name}`);
      if (lamp) { const on = !!v[`axis:${W.axis}:${n}`]; lamp.classList.toggle("on", on); lamp.setAttribute("aria-label", `${name} switch: ${on ? "on" : "off"}`); }
    }
  } catch (_) { /* the next tick tries again */ }
}

async function watchSearch(w, items) {
  if (W.active !== w || !$("wiz-rfs-status")) return;
  watchSwitches(items);
  try {
    const m = await api(`api/motion/${W.axis}`);
    const v = await readItems([axisItem(197)]);
    const active = m.rfs_status !== 0 && m.rfs_status !== null;
    if (active) w.searching = true;
    $("wiz-rfs-status").textContent = m.rfs_status === null ? "n/a" : active ? `active (${m.rfs_status})`
      : w.searching ? "done: the origin is set" : "not active";
    $("wiz-rfs-position").textContent = `${fmt(units().position(W.axis, m.position))} ${units().positionUnit(W.axis)}`;
    $("wiz-rfs-last").textContent = v[`axis:${W.axis}:197`] ?? "-";
  } catch (_) { /* again at the next tick */ }
}

// ---------------------------------------------------------------- encoder
function encoderSpec() {
  const a = W.axis, caps = ov().capabilities, prescaler = caps.encoder === "prescaler";
  return {
    title: "Encoder",
    reads: () => [210, 212, 140, ...(W.params[202] ? [202] : [])].map(n => axisItem(n)),
    steps: [
      {title: prescaler ? "Prescaler" : "Resolution", body: w => {
        const v = w.e?.p ?? w.values[`axis:${a}:210`];
        if (!prescaler) {
          return [el("p", {class: "hint"}, `${W.params[210].description} With AP 202 (full steps per round) set, the module converts the encoder to microsteps (manual 6.2).`),
            field("wiz-encoder", "encoder counts per round (AP 210)", v, {type: "number", min: 0, step: 1})];
        }
        const code = w.values[`axis:${a}:140`], steps = 200 * 2 ** code;
        const match = Math.round(512 * steps / caps.encoder_counts);
        return [el("p", {class: "hint"}, `AP 210 is the prescaler p: the encoder counts are scaled by p/512 (PD86-1180 manual 7.2). ` +
            `The encoder has ${caps.encoder_counts} counts per round; to count in microsteps (AP 140 = ${code}: ${steps} per round) p = 512 × ${steps} / ${caps.encoder_counts} = ${match}.`),
          field("wiz-encoder", "prescaler p (AP 210)", v === undefined ? match : v & ~4, {type: "number", min: 0, step: 1},
            el("button", {id: "wiz-encoder-match", onclick: () => { $("wiz-encoder").value = match; }}, "match the microsteps")),
          ...(caps.null_channel ? [el("label", {class: "wizard-field"}, el("input", {type: "checkbox", id: "wiz-encoder-null", ...(v & 4 ? {checked: ""} : {})}),
            " clear the encoder at the next null channel (+4)")] : [])];
      }, check: w => {
        let p = num("wiz-encoder");
        if (prescaler && $("wiz-encoder-null") && $("wiz-encoder-null").checked) p += 4;
        if (!Number.isInteger(p) || !inRange(210, p)) return `AP 210: ${p} is not allowed on the ${ov().module}`;
        if (prescaler && [1, 2, 4, 16].includes(p)) return "the values 1, 2, 4 and 16 must not be used for p (manual 7.2)";
        w.e = {...(w.e || {}), p};
        return "";
      }},
      {title: "Deviation", body: w => [
        el("p", {class: "hint"}, W.params[212].description),
        field("wiz-deviation", "maximum deviation (AP 212)", w.e.deviation ?? w.values[`axis:${a}:212`], {type: "number", min: 0, step: 1}, "encoder steps (0: off)")],
      check: w => {
        const d = num("wiz-deviation");
        if (!Number.isInteger(d) || !inRange(212, d)) return `AP 212: ${W.params[212].min}…${W.params[212].max}`;
        w.e = {...w.e, deviation: d};
        return "";
      }},
    ],
    writes: w => [{...axisItem(210, w.e.p), label: prescaler ? `prescaler ${w.e.p & ~4}/512` : "encoder counts per round"},
                  {...axisItem(212, w.e.deviation), label: w.e.deviation ? "stop beyond this deviation" : "deviation check off"}],
    run: {title: "Check", body: w => {
      W.timer = setInterval(() => watchEncoder(w), 300);
      return [el("p", {}, "Move the axis (Motion view or console) and compare: actual position (AP 1) ", el("b", {id: "wiz-enc-pos"}, "-"),
        ", encoder (AP 209) ", el("b", {id: "wiz-enc-value"}, "-"), ", difference ", el("b", {id: "wiz-enc-diff"}, "-"))];
    }},
  };
}

async function watchEncoder(w) {
  if (W.active !== w || !$("wiz-enc-pos")) return;
  try {
    const v = await readItems([axisItem(1), axisItem(209)]);
    const p = v[`axis:${W.axis}:1`], e = v[`axis:${W.axis}:209`];
    $("wiz-enc-pos").textContent = p; $("wiz-enc-value").textContent = e;
    $("wiz-enc-diff").textContent = p === null || e === null ? "-" : p - e;
  } catch (_) { /* again */ }
}

// ---------------------------------------------------------------- the view
const SPECS = {motor: motorSpec, reference: referenceSpec, encoder: encoderSpec};

async function loadParams() {
  const axis = W.axis;
  const [a, g] = await Promise.all([api(`api/params/axis/${axis}`), api("api/params/global")]);
  if (axis !== W.axis) return;
  W.params = Object.fromEntries(a.params.map(p => [p.number, p]));
  W.globals = Object.fromEntries(g.params.map(p => [`${p.bank}:${p.number}`, p]));
}

function cards() {
  const card = (key, title, text) => el("div", {class: "wizard-card"}, el("h3", {}, title), el("p", {class: "hint"}, text),
    el("button", {id: `wizard-open-${key}`, class: "primary", onclick: async () => {
      if (!W.params[6] && !W.params[193]) await loadParams();
      open(SPECS[key]());
    }}, `Set up ${title.toLowerCase()}…`));
  return el("div", {class: "wizard-cards"},
    card("motor", "Motor", "Run and standby current in mA, microstep resolution, speed and acceleration in rpm, rps or your unit."),
    card("reference", "Reference search", "Pick a mode from the manual's descriptions, set switch polarity and speeds, run it and watch the switches."),
    card("encoder", "Encoder", ov().capabilities.encoder === "prescaler" ? "Prescaler and maximum deviation." : "Encoder resolution and maximum deviation."));
}

OpenTMCL.registerView("setup", {
  mount(root, ctx) {
    W.ctx = ctx;
    if (!ctx.overview) return;
    const axes = Array.from({length: ctx.overview.axes}, (_, i) => el("option", {value: i}, `${i}`));
    root.replaceChildren(el("h2", {}, "Set-up wizards"),
      el("div", {class: "toolbar"}, el("label", {}, "Axis ", el("select", {id: "wizard-axis", onchange: async e => {
        if (W.active) await cancel();
        W.axis = Number(e.target.value); W.params = {};
      }}, ...axes)),
        el("span", {class: "hint"}, "Nothing is sent before Apply; Cancel writes back what Apply changed; Finish keeps it (and stores it in the EEPROM when asked).")),
      cards(), el("div", {id: "wizard-panel", class: "tool-panel", hidden: ""}));
  },
  show() { if (!W.params[6]) loadParams().catch(e => log(`set-up: ${e.message}`, "err")); },
});
})();
