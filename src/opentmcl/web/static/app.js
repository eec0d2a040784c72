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

const VIEWS = ["overview", "motion", "parameters", "charts", "program", "io"];
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
      row("position", "position"), row("target", "target"), row(`velocity [${ov.velocity_unit}]`, "velocity"),
      row("load value", "load"), row("run current", "max_current", "AP 6 maximum current: % of the module's maximum (raw value)"),
      row("current", "current", "AP 180 actual current: (n+1)/32 of CS (raw value n)"),
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
  last.p.forEach((v, i) => { const e = $(`axis-${i}-position`); if (e) e.textContent = v ?? "-"; });
  last.v.forEach((v, i) => { const e = $(`axis-${i}-velocity`); if (e) e.textContent = v ?? "-"; });
}

function lamp(id, on) {
  const e = $(id);
  if (!e) return;
  e.classList.toggle("on", !!on);
  e.setAttribute("aria-label", `${e.title}: ${on ? "on" : "off"}`);
}

// Currents in the manuals' terms, the raw value beside: AP 6 "255 means 100% of the module's maximum
// current", AP 180 "0..31 = 1/32 .. 32/32 of CS" (TMCM-6212 manual 4.1).
function currentText(key, v) {
  if (v === null || v === undefined) return "n/a";
  if (key === "max_current") return `${Math.round(v * 100 / 255)} % (${v})`;
  return `${v + 1}/32 CS (${v})`;
}

function onState(st) {
  D.connected = st.connected;
  setConnection();
  st.axes.forEach((a, i) => {
    const set = (k, v) => { const e = $(`axis-${i}-${k}`); if (e) e.textContent = v ?? "n/a"; };
    set("target", a.target_position); set("load", a.load);
    set("max_current", currentText("max_current", a.max_current)); set("current", currentText("current", a.current));
    lamp(`axis-${i}-reached`, a.target_reached); lamp(`axis-${i}-home`, a.home);
    lamp(`axis-${i}-left`, a.left); lamp(`axis-${i}-right`, a.right);
  });
  updateIo(st.io);
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
          try { await api("api/io/output", {bank: p.bank, port: p.port, value: e.target.checked ? 1 : 0}); }
          catch (err) { log(err.message, "err"); }
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
  $("io-panel").replaceChildren(el("table", {}, ...rows),
    el("p", {class: "hint"}, ov.virtual ? "Virtual module: inputs can be forced." :
                                           "Inputs of a real module follow its wiring."));
}

async function force(p, value) {
  try { await api("api/io/force", {bank: p.bank, port: p.port, value}); }
  catch (err) { log(err.message, "err"); }
}

function updateIo(io) {
  for (const p of io || []) {
    const key = `${p.bank}-${p.port}`;
    const v = $(`io-val-${key}`);
    if (v) v.textContent = (p.value ?? "n/a") + (p.forced !== null && p.forced !== undefined ? " (forced)" : "");
    const cb = $(`io-out-${key}`);
    if (cb && document.activeElement !== cb) cb.checked = !!p.value;
  }
}

// ---------------------------------------------------------------- stop all
// MST to every axis of every module on the bus and the program stopped (POST ../../api/stop-all).
async function stopAll() {
  const out = $("stop-all-result");
  out.className = "busy"; out.textContent = "stopping…";
  log("> STOP ALL: program stop (128) and MST on every axis of every module (served or found by the scan)", "req");
  for (const ctl of PENDING) ctl.abort();
  PENDING.clear();
  try {
    const r = await api("../../api/stop-all", {}, {keep: true});
    out.replaceChildren(...r.modules.map(m => el("span", {class: m.ok ? "ok" : "err", title: m.errors.join("; ")},
      `${m.module} @${m.address}: ${m.ok ? "stopped" : "error"}`)));
    out.className = r.ok ? "ok" : "err";
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
}
document.addEventListener("DOMContentLoaded", main);
