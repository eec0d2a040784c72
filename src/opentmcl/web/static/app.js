// OpenTMCL dashboard shell: plain JavaScript, no build step, no CDN, loaded before the views.
// The page of one module at /m/ADDRESS/: every request path is relative to it.
// Views (params.js, charts.js, editor.js, ...) call OpenTMCL.registerView(name, {mount, show, hide}).
"use strict";
const $ = id => document.getElementById(id);
const el = (tag, attrs = {}, ...kids) => {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "class") e.className = v; else if (k.startsWith("on")) e.addEventListener(k.slice(2), v);
    else if (v !== undefined && v !== null) e.setAttribute(k, v);
  }
  for (const k of kids) e.append(k instanceof Node ? k : document.createTextNode(String(k)));
  return e;
};

// Every POST carries X-OpenTMCL: 1, a header a cross-site form cannot send (docs/dashboard.md).
// The requests under way: STOP ALL aborts them first, so that the browser's few connections per
// server (six) cannot keep it waiting, and a command still queued is not sent after the stop.
const PENDING = new Set();
async function api(path, body, {keep = false} = {}) {
  const ctl = new AbortController();
  const opts = body === undefined ? {signal: ctl.signal} :
    {method: "POST", headers: {"Content-Type": "application/json", "X-OpenTMCL": "1"},
     body: JSON.stringify(body), signal: ctl.signal};
  if (!keep) PENDING.add(ctl);
  try {
    const r = await fetch(path, opts);
    let data = {};
    try { data = await r.json(); } catch (_) { /* not JSON */ }
    if (ctl.signal.aborted) throw new Error("cancelled by STOP ALL");
    if (!r.ok) throw new Error(data.error || r.statusText);
    return data;
  } catch (e) {
    if (e.name === "AbortError") throw new Error("cancelled by STOP ALL");
    throw e;
  } finally { PENDING.delete(ctl); }
}

const VIEWS = ["overview", "motion", "tuning", "setup", "parameters", "charts", "program", "io", "bus"];
const D = {overview: null, charts: {}, wsOpen: false, connected: true, history: [], historyPos: 0,
           views: {}, current: null, stateSubs: [], sampleSubs: []};
window.dashboard = D;  // for the browser tests and the curious

window.OpenTMCL = {
  registerView(name, view) { D.views[name] = view; },
  api, el, log,
  send: line => sendConsole(line),  // one instruction through the console, logged with its reply
};

// ---------------------------------------------------------------- navigation between views
function viewFromHash() {
  const name = location.hash.replace(/^#/, "");
  return VIEWS.includes(name) ? name : "overview";
}

function showView(name) {
  if (name === D.current) return;
  const old = D.current && D.views[D.current];
  if (old && old.hide) { try { old.hide(); } catch (e) { log(e.message, "err"); } }
  for (const sec of document.querySelectorAll("section.view")) sec.hidden = sec.dataset.view !== name;
  for (const a of document.querySelectorAll("#views-nav a")) {
    a.classList.toggle("active", a.dataset.view === name);
    if (a.dataset.view === name) a.setAttribute("aria-current", "page"); else a.removeAttribute("aria-current");
  }
  D.current = name;
  const view = D.views[name];
  if (view && view.show) { try { view.show(); } catch (e) { log(e.message, "err"); } }
}

function contextFor(name) {
  return {
    api, log, el, send: sendConsole,
    get overview() { return D.overview; },
    onState(cb) { D.stateSubs.push(cb); },
    onSamples(cb) { D.sampleSubs.push(cb); },
    isVisible() { return D.current === name; },
  };
}

function mountViews() {
  for (const [name, view] of Object.entries(D.views)) {
    const root = $(`view-${name}`);
    if (!root) { log(`no place for the view "${name}"`, "err"); continue; }
    try { view.mount(root, contextFor(name)); } catch (e) { log(`${name}: ${e.message}`, "err"); }
  }
}

function notify(subs, data) {
  for (const cb of subs) { try { cb(data); } catch (e) { console.error(e); } }
}

// ---------------------------------------------------------------- overview and axis cards
function showOverview(ov) {
  D.overview = ov;
  $("ov-module").textContent = ov.module;
  $("ov-version").textContent = ov.version;
  $("ov-address").textContent = ov.address;
  $("ov-url").textContent = ov.url || "-";
  document.title = `OpenTMCL ${ov.module}`;
  const cards = $("axis-cards");
  cards.replaceChildren();
  for (let i = 0; i < ov.axes; i++) {
    const row = (label, key, title) => el("div", {class: "row", title},
      el("span", {}, label), el("span", {id: `axis-${i}-${key}`}, "-"));
    cards.append(el("div", {class: "axis-card", id: `axis-${i}`},
      el("h3", {}, `Axis ${i}`),
      row(el("span", {}, "position ", el("span", {class: "unit", id: `axis-${i}-position-unit`}, "")), "position"),
      row("target", "target"),
      row(el("span", {}, "velocity ", el("span", {class: "unit", id: `axis-${i}-velocity-unit`}, `[${ov.velocity_unit}]`)), "velocity"),
      row("load value", "load"), row("run current", "max_current", "AP 6 maximum current in mA RMS from the module's current scale (raw value 0..255)"),
      row("current", "current", "AP 180 actual current: (n+1)/32 of the full scale, in mA RMS (raw value n)"),
      el("div", {class: "lamps"},
        el("span", {class: "lamp reached", id: `axis-${i}-reached`, title: "target position reached (AP 8)"}, "reached"),
        el("span", {class: "lamp", id: `axis-${i}-home`, title: "home switch (AP 9)"}, "home"),
        el("span", {class: "lamp", id: `axis-${i}-left`, title: "left limit switch (AP 11)"}, "left"),
        el("span", {class: "lamp", id: `axis-${i}-right`, title: "right limit switch (AP 10)"}, "right"))));
  }
  buildIo(ov);
}

function setConnection() {
  const c = $("ov-connection");
  const ok = D.wsOpen && D.connected;
  c.className = "conn " + (ok ? "ok" : "bad");
  c.textContent = !D.wsOpen ? "dashboard offline" : D.connected ? "connected" : "module not answering";
}

function onSamples(samples) {
  notify(D.sampleSubs, samples);
  const last = samples[samples.length - 1];
  if (!last) return;
  last.p.forEach((v, i) => { const e = $(`axis-${i}-position`); if (e) e.textContent = shown("position", i, v); });
  last.v.forEach((v, i) => { const e = $(`axis-${i}-velocity`); if (e) e.textContent = shown("velocity", i, v); });
  // the chip of the last STOP ALL goes once an axis moves again after every axis stood still
  if (D.stopped) {
    if (last.v.every(v => !v)) D.stopped.still = true;
    else if (D.stopped.still) clearStopChip("an axis moves again");
  }
}

function lamp(id, on) {
  const e = $(id);
  if (!e) return;
  e.classList.toggle("on", !!on);
  e.setAttribute("aria-label", `${e.title}: ${on ? "on" : "off"}`);
}

// Positions and velocities in the axis's units (static/units.js); raw while those are not known.
function shown(kind, axis, v) {
  const u = window.OpenTMCL.units;
  if (v === null || v === undefined) return "-";
  if (!u || !u.info) return String(v);
  const x = kind === "position" ? u.position(axis, v) : u.velocity(axis, v);
  return x === null ? String(v) : u.fmt(x, 6);
}

function unitLabels() {
  const u = window.OpenTMCL.units;
  if (!D.overview || !u || !u.info) return;
  for (let i = 0; i < D.overview.axes; i++) {
    const p = $(`axis-${i}-position-unit`), v = $(`axis-${i}-velocity-unit`);
    if (p) p.textContent = `[${u.positionUnit(i)}]`;
    if (v) v.textContent = `[${u.velocityUnit(i)}]`;
  }
}

// Currents in mA RMS from the module's documented current scale (web/units.py, the profile's
// current_scale), the raw value beside: AP 6 "255 means 100% of the maximum current of the module",
// AP 180 "0...31: 1/32, 2/32, ... 32/32" (TMCM-6212 manual 4.1). Without a scale: the manual's terms.
function currentText(key, v) {
  if (v === null || v === undefined) return "n/a";
  const u = window.OpenTMCL.units;
  const ma = u && u.currentScale() ? (key === "max_current" ? u.currentMa(v) : u.scaleMa(v)) : null;
  if (ma !== null) return `${Math.round(ma)} mA (${v})`;
  if (key === "max_current") return `${Math.round(v * 100 / 255)} % (${v})`;
  return `${v + 1}/32 CS (${v})`;
}

function onState(st) {
  D.connected = st.connected;
  setConnection();
  st.axes.forEach((a, i) => {
    const set = (k, v) => { const e = $(`axis-${i}-${k}`); if (e) e.textContent = v ?? "n/a"; };
    set("target", shown("position", i, a.target_position)); set("load", a.load);
    set("max_current", currentText("max_current", a.max_current)); set("current", currentText("current", a.current));
    lamp(`axis-${i}-reached`, a.target_reached); lamp(`axis-${i}-home`, a.home);
    lamp(`axis-${i}-left`, a.left); lamp(`axis-${i}-right`, a.right);
  });
  updateIo(st.io);
  if (D.stopped && st.program) {  // ... or once the program runs again after it was seen stopped
    if (st.program.mode !== 1) D.stopped.program = true;
    else if (D.stopped.program) clearStopChip("the program runs again");
  }
  notify(D.stateSubs, st);
}

function connect() {
  const url = new URL("ws", location.href);
  url.protocol = location.protocol === "https:" ? "wss:" : "ws:";
  const ws = new WebSocket(url, "opentmcl");  // the server refuses an upgrade without it
  ws.onopen = () => { D.wsOpen = true; setConnection(); };
  ws.onclose = () => { D.wsOpen = false; setConnection(); setTimeout(connect, 1000); };
  ws.onmessage = ev => {
    const msg = JSON.parse(ev.data);
    if (msg.type === "hello") { if (!D.overview) showOverview(msg.overview); }
    else if (msg.type === "samples") onSamples(msg.samples);
    else if (msg.type === "state") onState(msg.state);
  };
}

// ---------------------------------------------------------------- module selector
async function setupModules() {
  const modules = await api("../../api/modules");  // every module the server serves
  const here = new URL(location.href).pathname;
  const sel = $("module-select");
  sel.replaceChildren(...modules.map(m => el("option", {value: m.url}, `${m.module} (address ${m.address})`)));
  const current = modules.find(m => m.url === here);
  if (current) sel.value = current.url;
  sel.addEventListener("change", () => location.assign(sel.value));
  $("module-choice").hidden = modules.length < 2;
}

// ---------------------------------------------------------------- direct-mode console
function log(text, cls) {
  const box = $("console-log");
  box.append(el("div", {class: cls}, text));
  box.scrollTop = box.scrollHeight;
}

async function sendConsole(line) {
  log(`> ${line}`, "req");
  try {
    const r = await api("api/console", {line});
    log(`  [${r.request.join(", ")}] ${r.text}`, r.ok ? "ok" : "err");
    return r;
  } catch (e) { log(`  ${e.message}`, "err"); return null; }
}

function setupConsole() {
  try { D.history = JSON.parse(localStorage.getItem("opentmcl-history") || "[]"); } catch (_) { D.history = []; }
  D.historyPos = D.history.length;
  $("console-form").addEventListener("submit", ev => {
    ev.preventDefault();
    const input = $("console-input"), line = input.value.trim();
    if (!line) return;
    if (D.history[D.history.length - 1] !== line) D.history.push(line);
    D.history = D.history.slice(-100);
    localStorage.setItem("opentmcl-history", JSON.stringify(D.history));
    D.historyPos = D.history.length;
    input.value = "";
    sendConsole(line);
  });
  $("console-input").addEventListener("keydown", ev => {
    if (ev.key !== "ArrowUp" && ev.key !== "ArrowDown") return;
    ev.preventDefault();
    D.historyPos = Math.max(0, Math.min(D.history.length, D.historyPos + (ev.key === "ArrowUp" ? -1 : 1)));
    ev.target.value = D.history[D.historyPos] || "";
  });
}

// ---------------------------------------------------------------- inputs and outputs
function buildIo(ov) {
  const rows = [el("tr", {}, el("th", {}, "port"), el("th", {}, "kind"), el("th", {}, "value"), el("th", {}, ""))];
  for (const p of ov.io) {
    const key = `${p.bank}-${p.port}`;
    let control = "";
    if (p.kind === "output") {
      control = el("input", {type: "checkbox", id: `io-out-${key}`, title: `SIO ${p.port}, ${p.bank}, 0/1`,
        onchange: async e => {
          const value = e.target.checked ? 1 : 0;
          log(`> SIO ${p.port}, ${p.bank}, ${value}`, "req");
          try {
            const r = await api("api/io/output", {bank: p.bank, port: p.port, value});
            log(`  ${p.name} = ${r.value}`, "ok");
          } catch (err) { log(`  ${err.message}`, "err"); }
        }});
    } else if (ov.virtual) {
      const input = el("input", {type: "number", id: `io-force-${key}`, min: p.min, max: p.max,
                                 value: p.kind === "analog" ? 0 : 1, style: "width:80px"});
      control = el("span", {},
        input,
        el("button", {onclick: () => force(p, Number(input.value))}, "force"),
        el("button", {onclick: () => force(p, null)}, "release"));
    }
    rows.push(el("tr", {}, el("td", {}, p.name), el("td", {}, `${p.kind} (bank ${p.bank})`),
                 el("td", {id: `io-val-${key}`}, "-"), el("td", {}, control)));
  }
  const analog = ov.io.some(p => p.kind === "analog");
  $("io-panel").replaceChildren(el("table", {}, ...rows),
    el("p", {class: "hint"}, ov.virtual ? "Virtual module: inputs can be forced; each action is logged in the console." :
                                           "Inputs of a real module follow its wiring."),
    ...(analog ? [el("p", {class: "hint", id: "io-analog-scale"}, "")] : []));
}

async function force(p, value) {
  log(value === null ? `> release ${p.name} (bank ${p.bank}, port ${p.port}; virtual module)`
                     : `> force ${p.name} (bank ${p.bank}, port ${p.port}) to ${value} (virtual module)`, "req");
  try { await api("api/io/force", {bank: p.bank, port: p.port, value}); log(`  ${value === null ? "released" : "forced"}`, "ok"); }
  catch (err) { log(`  ${err.message}`, "err"); }
}

// Analog inputs in volts where the profile carries a manual's scale; otherwise ADC counts, and the
// page says that no manual gives the scale (docs/assumptions.md).
function ioText(p) {
  if (p.value === null || p.value === undefined) return "n/a";
  const u = window.OpenTMCL.units, port = D.overview && D.overview.io.find(q => q.bank === p.bank && q.port === p.port);
  if (p.kind !== "analog" || !u || !port) return String(p.value);
  const v = u.volts(p.value, port.max);
  return v === null ? `${p.value} counts` : `${u.fmt(v, 3)} V (${p.value})`;
}

function updateIo(io) {
  for (const p of io || []) {
    const key = `${p.bank}-${p.port}`;
    const v = $(`io-val-${key}`);
    if (v) v.textContent = ioText(p) + (p.forced !== null && p.forced !== undefined ? " (forced)" : "");
    const cb = $(`io-out-${key}`);
    if (cb && document.activeElement !== cb) cb.checked = !!p.value;
  }
}

// ---------------------------------------------------------------- stop all
// MST to every axis of every module on the bus and the program stopped (POST ../../api/stop-all).
// The result chips of the last STOP ALL, cleared once the machine runs again (issue 31 item 6).
function clearStopChip(why) {
  D.stopped = null;
  const out = $("stop-all-result");
  out.replaceChildren(); out.className = ""; out.title = why || "";
}

async function stopAll() {
  const out = $("stop-all-result");
  D.stopped = null;
  out.className = "busy"; out.textContent = "stopping…";
  log("> STOP ALL: program stop (128) and MST on every axis of every module (served or found by the scan)", "req");
  for (const ctl of PENDING) ctl.abort();
  PENDING.clear();
  try {
    const r = await api("../../api/stop-all", {}, {keep: true});
    out.replaceChildren(...r.modules.map(m => el("span", {class: m.ok ? "ok" : "err", title: m.errors.join("; ")},
      `${m.module} @${m.address}: ${m.ok ? "stopped" : "error"}`)));
    out.className = r.ok ? "ok" : "err";
    D.stopped = {still: false, program: false};
    if (r.scan_cancelled) log("  the module scan was cancelled", "req");
    for (const m of r.modules) {
      log(`  ${m.module} (address ${m.address}): ${m.ok ? `MST ${m.axes_stopped.join(", ")}` : m.error}`, m.ok ? "ok" : "err");
    }
  } catch (e) { out.className = "err"; out.textContent = `stop failed: ${e.message}`; log(`  ${e.message}`, "err"); }
}

function setupStopAll() {
  $("btn-stop-all").addEventListener("click", stopAll);
  // Capture phase: Escape stops everything wherever the focus is, inputs and the editor included.
  window.addEventListener("keydown", ev => {
    if (ev.key !== "Escape" || ev.repeat) return;
    ev.preventDefault();
    stopAll();
  }, true);
}

window.OpenTMCL.stopAll = () => stopAll();

// ---------------------------------------------------------------- start
async function main() {
  setupStopAll();
  setupConsole();
  try { showOverview(await api("api/overview")); } catch (e) { log(e.message, "err"); }
  mountViews();
  showView(viewFromHash());
  window.addEventListener("hashchange", () => showView(viewFromHash()));
  try { await setupModules(); } catch (e) { log(e.message, "err"); }
  connect();
  const u = window.OpenTMCL.units;
  if (u) {
    u.onChange(() => { unitLabels(); if (D.overview) updateAnalogNote(); });
    u.ready.then(() => { unitLabels(); updateAnalogNote(); });
  }
}

function updateAnalogNote() {
  const note = $("io-analog-scale"), u = window.OpenTMCL.units;
  if (!note || !u || !u.info) return;
  note.textContent = u.info.analog_volts ? `Analog inputs in volts: full scale ${u.info.analog_volts} V (module profile).`
    : `Analog inputs in ADC counts: the ${D.overview.module} manual gives no voltage scale for them.`;
}
document.addEventListener("DOMContentLoaded", main);
