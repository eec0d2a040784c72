// Physical units (docs/dashboard.md "Units"): each axis shows velocities, accelerations and positions
// in µsteps/pps, rps, rpm or a user scale (e.g. mm with a lead per round and a gear ratio), currents
// in mA from the module's documented current scale, analog inputs in volts where a manual gives the
// scale. The server (web/units.py) gives one factor per axis from the manuals' formulas; the unit
// setting of each axis is given once, kept on the server (and so in the parameter export) and in
// this browser. Loaded after app.js and before the views.
"use strict";
(() => {
const {api, el, log} = window.OpenTMCL;
const KEY = `opentmcl-units ${location.pathname}`;
const U = {info: null, settings: {}, subs: [], ready: null};
const KINDS = {pps: "µsteps, pps", rps: "rounds, rps", rpm: "rounds, rpm", user: "user scale"};

function local() { try { return JSON.parse(localStorage.getItem(KEY) || "{}") || {}; } catch (_) { return {}; } }
function keep() { try { localStorage.setItem(KEY, JSON.stringify(U.settings)); } catch (_) { /* private mode */ } }

async function reload() {
  const r = await api("api/units");
  U.info = r;
  const mine = local();
  U.settings = {...mine, ...r.settings};   // the server's (an imported file's) win
  for (const [axis, s] of Object.entries(mine)) {  // given in this browser before: the server keeps them too
    if (!r.settings[axis]) { try { await api("api/units", {axis: Number(axis), setting: s}); } catch (_) { delete U.settings[axis]; } }
  }
  keep();
  for (const cb of U.subs) { try { cb(); } catch (e) { console.error(e); } }
  return r;
}

function axisInfo(axis) { return U.info && U.info.axes[axis] || null; }
function setting(axis) { return U.settings[axis] || {kind: "pps"}; }

async function setSetting(axis, s) {
  const r = await api("api/units", {axis, setting: s});
  U.settings[axis] = r.setting;
  keep();
  log(`axis ${axis}: units ${describe(axis)}`, "ok");
  for (const cb of U.subs) { try { cb(); } catch (e) { console.error(e); } }
}

function describe(axis) {
  const s = setting(axis);
  return s.kind === "user" ? `${s.name} (${s.per_round} ${s.name} per output round, gear ${s.gear}:1)` : KINDS[s.kind];
}

// Microsteps per motor round: 2^AP140 x full steps (AP202, or 200), TMCM-6212 manual 6.5.
function perRound(axis) { const i = axisInfo(axis); return i && i.microsteps ? i.microsteps * i.fullsteps : null; }

// One motor round in the unit of the axis (rounds for rps/rpm, the user unit through lead and gear).
function roundsToUnit(axis, rounds) {
  const s = setting(axis);
  return s.kind === "user" ? rounds / s.gear * s.per_round : rounds;
}
function unitToRounds(axis, x) {
  const s = setting(axis);
  return s.kind === "user" ? x * s.gear / s.per_round : x;
}

const units = {
  kinds: KINDS,
  get info() { return U.info; },
  reload, setting, set: setSetting, describe, onChange(cb) { U.subs.push(cb); },
  axis: axisInfo,
  // --- velocity: the module's unit (pps or internal) <-> the axis's unit
  velocityUnit(axis) {
    const s = setting(axis);
    return {pps: "pps", rps: "rps", rpm: "rpm", user: `${s.name}/s`}[s.kind];
  },
  velocity(axis, raw) {
    const i = axisInfo(axis), n = perRound(axis);
    if (raw === null || raw === undefined || !i) return null;
    const pps = raw * i.pps_per_unit, s = setting(axis);
    if (s.kind === "pps" || !n) return pps;
    const rps = roundsToUnit(axis, pps / n);
    return s.kind === "rpm" ? rps * 60 : rps;
  },
  velocityRaw(axis, value, microsteps) {  // microsteps: a per-round count to use instead of the module's (wizards)
    const i = axisInfo(axis), s = setting(axis);
    const n = microsteps || perRound(axis);
    let pps = value;
    if (s.kind !== "pps" && n) pps = unitToRounds(axis, s.kind === "rpm" ? value / 60 : value) * n;
    return Math.round(pps / i.pps_per_unit);
  },
  // --- acceleration (pps^2 / internal) <-> unit/s^2 (rpm kind: rpm/s)
  accelUnit(axis) {
    const s = setting(axis);
    return {pps: "pps²", rps: "rps²", rpm: "rpm/s", user: `${s.name}/s²`}[s.kind];
  },
  accel(axis, raw) {
    const i = axisInfo(axis), n = perRound(axis);
    if (raw === null || raw === undefined || !i) return null;
    const pps2 = raw * i.pps2_per_unit, s = setting(axis);
    if (s.kind === "pps" || !n) return pps2;
    const r = roundsToUnit(axis, pps2 / n);
    return s.kind === "rpm" ? r * 60 : r;
  },
  accelRaw(axis, value, microsteps) {
    const i = axisInfo(axis), s = setting(axis);
    const n = microsteps || perRound(axis);
    let pps2 = value;
    if (s.kind !== "pps" && n) pps2 = unitToRounds(axis, s.kind === "rpm" ? value / 60 : value) * n;
    return Math.round(pps2 / i.pps2_per_unit);
  },
  // --- position: microsteps <-> rounds or the user unit
  positionUnit(axis) {
    const s = setting(axis);
    return {pps: "µsteps", rps: "rev", rpm: "rev", user: s.name}[s.kind];
  },
  position(axis, raw) {
    const n = perRound(axis), s = setting(axis);
    if (raw === null || raw === undefined) return null;
    return s.kind === "pps" || !n ? raw : roundsToUnit(axis, raw / n);
  },
  positionRaw(axis, value) {
    const n = perRound(axis), s = setting(axis);
    return Math.round(s.kind === "pps" || !n ? value : unitToRounds(axis, value) * n);
  },
  // --- currents: AP6/AP7/AP183 (0..255) and AP180 (0..31) in mA RMS, from the profile's scale
  currentScale() { return U.info ? U.info.current : null; },
  currentMa(raw) {
    const sc = units.currentScale();
    if (!sc || raw === null || raw === undefined) return null;
    if (raw <= 0) return 0;  // 0: no current (AP204's stand-still option on the TMCM-6212)
    return sc.steps === 32 ? ((raw >> 3) + 1) / 32 * sc.rms_ma : raw * sc.rms_ma / 255;
  },
  currentRaw(ma) {  // the AP6/AP7 value for ma: the top of its step of 32 (255 = 100 %), or the formula
    const sc = units.currentScale();
    if (!sc || !(ma > 0)) return 0;
    if (sc.steps === 32) return Math.max(0, Math.min(31, Math.round(ma / sc.rms_ma * 32) - 1)) * 8 + 7;
    return Math.max(0, Math.min(255, Math.round(ma * 255 / sc.rms_ma)));
  },
  scaleMa(n) {  // AP180: "0...31: 1/32, 2/32, ... 32/32" of the full scale
    const sc = units.currentScale();
    return !sc || n === null || n === undefined ? null : (n + 1) / 32 * sc.rms_ma;
  },
  // --- analog inputs in volts, where a manual (the profile) gives the scale
  volts(value, max) {
    const v = U.info && U.info.analog_volts;
    return v && value !== null && value !== undefined ? value / max * v : null;
  },
  fmt(x, digits = 4) {
    if (x === null || x === undefined || !Number.isFinite(x)) return "n/a";
    if (Number.isInteger(x)) return String(x);
    const a = Math.abs(x);
    return a >= 10 ** digits ? String(Math.round(x)) : String(Number(x.toPrecision(digits)));
  },
};

// The unit choice of one axis: a small form, used by the motion view and the wizards (`prefix`
// keeps the ids of two forms of the same axis apart).
units.chooser = function (axis, onSaved, prefix = "units") {
  const s = setting(axis);
  const kind = el("select", {id: `${prefix}-${axis}-kind`, title: "units of this axis (kept with the parameter export)"},
    ...Object.entries(KINDS).map(([k, t]) => el("option", {value: k}, t)));
  kind.value = s.kind;
  const name = el("input", {id: `${prefix}-${axis}-name`, value: s.name || "mm", size: 4, title: "name of the user unit"});
  const per = el("input", {id: `${prefix}-${axis}-per-round`, type: "number", value: s.per_round || 5, step: "any", min: 0,
                           style: "width:70px", title: "user units per output round (e.g. the lead of a screw in mm)"});
  const gear = el("input", {id: `${prefix}-${axis}-gear`, type: "number", value: s.gear || 1, step: "any", min: 0,
                            style: "width:60px", title: "motor rounds per output round (gear ratio)"});
  const user = el("span", {class: "units-user"}, name, " ", per, " per round, gear ", gear, ":1 ");
  const save = el("button", {id: `${prefix}-${axis}-save`, onclick: async () => {
    const v = {kind: kind.value};
    if (v.kind === "user") Object.assign(v, {name: name.value.trim(), per_round: Number(per.value), gear: Number(gear.value)});
    try { await setSetting(axis, v); if (onSaved) onSaved(); } catch (e) { log(`axis ${axis} units: ${e.message}`, "err"); }
  }}, "set");
  const sync = () => { user.hidden = kind.value !== "user"; };
  kind.addEventListener("change", sync);
  sync();
  const follow = () => {  // a setting made elsewhere (another form, an imported file) shows here too
    if (!kind.isConnected) { U.subs = U.subs.filter(cb => cb !== follow); return; }
    const now = setting(axis);
    if (document.activeElement !== kind) { kind.value = now.kind; sync(); }
    if (now.kind === "user") { name.value = now.name; per.value = now.per_round; gear.value = now.gear; }
  };
  U.subs.push(follow);
  return el("span", {class: "units-chooser"}, "units ", kind, " ", user, save);
};

window.OpenTMCL.units = units;
U.ready = new Promise(resolve => {
  document.addEventListener("DOMContentLoaded", () => {
    reload().then(resolve, e => { log(`units: ${e.message}`, "err"); resolve(null); });
  });
});
units.ready = U.ready;
})();
