// OpenTMCL dashboard: plain JavaScript, no build step, no CDN.
// The page of one module at /m/ADDRESS/: every request path is relative to it.
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
async function api(path, body) {
  const opts = body === undefined ? {} :
    {method: "POST", headers: {"Content-Type": "application/json", "X-OpenTMCL": "1"},
     body: JSON.stringify(body)};
  const r = await fetch(path, opts);
  let data = {};
  try { data = await r.json(); } catch (_) { /* not JSON */ }
  if (!r.ok) throw new Error(data.error || r.statusText);
  return data;
}

const D = {overview: null, charts: {}, wsOpen: false, connected: true, breakpoints: new Set(),
           errorLines: new Set(), currentLine: null, history: [], historyPos: 0, ioBuilt: false};
window.dashboard = D;  // for the browser tests and the curious

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
  const chartAxes = $("chart-axes");
  chartAxes.replaceChildren();
  const sel = $("param-axis");
  const keep = sel.value;
  sel.replaceChildren();
  for (let i = 0; i < ov.axes; i++) {
    const row = (label, key) => el("div", {class: "row"}, el("span", {}, label), el("span", {id: `axis-${i}-${key}`}, "-"));
    cards.append(el("div", {class: "axis-card", id: `axis-${i}`},
      el("h3", {}, `Axis ${i}`),
      row("position", "position"), row("target", "target"), row(`velocity [${ov.velocity_unit}]`, "velocity"),
      row("load value", "load"), row("current", "current"),
      el("div", {class: "row"}, el("span", {}, "status"), el("span", {},
        el("span", {class: "lamp reached", id: `axis-${i}-reached`, title: "target position reached (AP 8)"}, "TR"),
        el("span", {class: "lamp", id: `axis-${i}-home`, title: "home switch (AP 9)"}, "H"),
        el("span", {class: "lamp", id: `axis-${i}-left`, title: "left limit switch (AP 11)"}, "L"),
        el("span", {class: "lamp", id: `axis-${i}-right`, title: "right limit switch (AP 10)"}, "R")))));
    const cb = el("input", {type: "checkbox", checked: "", onchange: e => {
      for (const c of Object.values(D.charts)) { c.visible[i] = e.target.checked; c.dirty = true; }
    }});
    chartAxes.append(el("label", {style: `color:${CHART_COLORS[i % CHART_COLORS.length]}`}, cb, ` axis ${i}`));
    sel.append(el("option", {value: i}, `${i}`));
  }
  if (keep && Number(keep) < ov.axes) sel.value = keep;
  $("vel-unit").textContent = ov.velocity_unit;
  for (const name of ["position", "velocity"]) {
    D.charts[name] = new LiveChart($(`chart-${name}`), ov.history_seconds || 60);
    D.charts[name].setAxes(ov.axes);
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
  for (const s of samples) {
    s.p.forEach((v, i) => D.charts.position.push(i, s.t, v));
    s.v.forEach((v, i) => D.charts.velocity.push(i, s.t, v));
  }
  const last = samples[samples.length - 1];
  if (!last) return;
  last.p.forEach((v, i) => { const e = $(`axis-${i}-position`); if (e) e.textContent = v ?? "-"; });
  last.v.forEach((v, i) => { const e = $(`axis-${i}-velocity`); if (e) e.textContent = v ?? "-"; });
}

function lamp(id, on) { const e = $(id); if (e) e.classList.toggle("on", !!on); }

function onState(st) {
  D.connected = st.connected;
  setConnection();
  st.axes.forEach((a, i) => {
    const set = (k, v) => { const e = $(`axis-${i}-${k}`); if (e) e.textContent = v ?? "n/a"; };
    set("target", a.target_position); set("load", a.load); set("current", a.current);
    lamp(`axis-${i}-reached`, a.target_reached); lamp(`axis-${i}-home`, a.home);
    lamp(`axis-${i}-left`, a.left); lamp(`axis-${i}-right`, a.right);
  });
  updateIo(st.io);
  showProgramState(st.program);
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

function animate() {
  for (const c of Object.values(D.charts)) c.draw();
  requestAnimationFrame(animate);
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
  } catch (e) { log(`  ${e.message}`, "err"); }
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

// ---------------------------------------------------------------- parameters
function paramRows(table, params, kind, index) {
  const filter = $("param-filter").value.trim().toLowerCase();
  const writableOnly = $("param-filter-writable").checked;
  const rows = [el("tr", {}, ...["#", "name", "value", "unit", "range", "access", ""].map(h => el("th", {}, h)))];
  for (const p of params) {
    if (writableOnly && !p.writable) continue;
    if (filter && !p.name.includes(filter) && !p.title.toLowerCase().includes(filter)) continue;
    const id = kind === "axis" ? `param-axis-${p.number}` : `param-global-${p.bank}-${p.number}`;
    let valueCell;
    if (p.writable) {
      const input = el("input", {id, value: p.value ?? "", "data-number": p.number});
      input.addEventListener("keydown", async ev => {
        if (ev.key !== "Enter") return;
        input.classList.remove("saved", "failed");
        const body = kind === "axis" ? {axis: index, number: p.number, value: input.value}
                                     : {bank: p.bank, number: p.number, value: input.value};
        try {
          const r = await api(`api/params/${kind}`, body);
          input.value = r.value; input.classList.add("saved");
        } catch (e) { input.classList.add("failed"); input.title = e.message; log(e.message, "err"); }
      });
      valueCell = el("td", {class: "num"}, input);
    } else {
      valueCell = el("td", {class: "num", id}, p.value ?? "-");
    }
    const range = p.values.length ? p.values.join(", ") : `${p.min} … ${p.max}`;
    const buttons = el("td", {});
    if (p.can_store) buttons.append(el("button", {onclick: () => storeParam(kind, p, index, false)}, "store"));
    if (p.can_restore) buttons.append(el("button", {onclick: () => storeParam(kind, p, index, true)}, "restore"));
    const label = kind === "global" ? `${p.number} (bank ${p.bank})` : `${p.number}`;
    rows.push(el("tr", {class: p.writable ? "" : "ro"}, el("td", {class: "num"}, label),
      el("td", {title: p.description || p.title}, p.title), valueCell, el("td", {}, p.unit),
      el("td", {}, range), el("td", {}, p.access), buttons));
  }
  table.replaceChildren(...rows);
}

async function storeParam(kind, p, index, restore) {
  try {
    await api("api/params/store", {kind, number: p.number, index: kind === "axis" ? index : p.bank, restore});
    log(`${restore ? "restored" : "stored"} ${kind} parameter ${p.number}`, "ok");
    if (restore) loadParams();
  } catch (e) { log(e.message, "err"); }
}

async function loadParams() {
  const axis = Number($("param-axis").value || 0);
  try {
    const [a, g] = await Promise.all([api(`api/params/axis/${axis}`), api("api/params/global")]);
    D.axisParams = a.params; D.globalParams = g.params;
    renderParams();
  } catch (e) { log(e.message, "err"); }
}

function renderParams() {
  if (!D.axisParams) return;
  paramRows($("param-axis-table"), D.axisParams, "axis", Number($("param-axis").value || 0));
  paramRows($("param-global-table"), D.globalParams, "global", 0);
}

// ---------------------------------------------------------------- program editor
const EXAMPLE = `// Move motor 0 back and forth (TMCM-6212 manual 2.4)
    SAP 4, 0, 51200        // maximum positioning speed
    SAP 5, 0, 51200        // maximum acceleration
    SGP 0, 2, 0            // user variable 0 counts the moves
Loop:
    MVP ABS, 0, 51200
    WAIT POS, 0, 0
    MVP ABS, 0, 0
    WAIT POS, 0, 0
    GGP 0, 2
    CALC ADD, 1
    AGP 0, 2
    JA Loop
`;

const SOURCE_KEY = `opentmcl-source ${location.pathname}`;  // each module keeps its own program

function editorLines() { return $("editor").value.split("\n").length; }

function renderGutter() {
  const n = editorLines(), gutter = $("editor-gutter"), back = $("editor-backdrop");
  const g = [], b = [];
  for (let i = 1; i <= n; i++) {
    const d = el("div", {id: `gutter-${i}`, class: D.breakpoints.has(i) ? "bp" : "", title: "toggle breakpoint"}, i);
    d.addEventListener("click", () => toggleBreakpoint(i));
    g.push(d);
    b.push(el("div", {id: `line-${i}`, class: i === D.currentLine ? "current" : D.errorLines.has(i) ? "error" : ""}, " "));
  }
  gutter.replaceChildren(...g);
  back.replaceChildren(...b);
  syncScroll();
}

function syncScroll() {
  const t = $("editor");
  $("editor-gutter").scrollTop = t.scrollTop;
  $("editor-backdrop").scrollTop = t.scrollTop;
}

async function toggleBreakpoint(line) {
  if (D.breakpoints.has(line)) D.breakpoints.delete(line); else D.breakpoints.add(line);
  renderGutter();
  if (D.downloaded) await pushBreakpoints();
}

async function pushBreakpoints() {
  try { await api("api/program/breakpoints", {lines: [...D.breakpoints]}); }
  catch (e) { message(e.message, true); }
}

function message(text, error) {
  const m = $("prog-message");
  m.textContent = text; m.className = error ? "err" : "";
}

function showErrors(errors) {
  D.errorLines = new Set(errors.map(e => e.line));
  $("asm-errors").replaceChildren(...errors.map(e => el("div", {class: "asm-error"}, `line ${e.line}, column ${e.column}: ${e.message}`)));
  renderGutter();
}

async function assembleOnly(download) {
  const source = $("editor").value;
  try {
    const r = await api(download ? "api/program/download" : "api/program/assemble", {source});
    showErrors(r.errors || []);
    if (!r.ok) { message(`${r.errors.length} error(s)`, true); return false; }
    if (download) {
      D.downloaded = true;
      await pushBreakpoints();
      message(`downloaded ${r.count} instructions`);
    } else {
      message(`assembled: ${r.count} instructions`);
    }
    return true;
  } catch (e) { message(e.message, true); return false; }
}

async function programAction(name) {
  try { showProgramState(await api(`api/program/${name}`, {})); message(name); }
  catch (e) { message(e.message, true); }
}

function showProgramState(p) {
  if (!p || p.mode === null || p.mode === undefined) return;
  $("prog-mode").textContent = p.mode_name + (p.waiting ? " (waiting)" : "") + (p.stepping_to_breakpoint ? " (to breakpoint)" : "");
  $("prog-pc").textContent = p.pc;
  $("prog-line").textContent = p.line ?? "-";
  $("prog-a").textContent = p.a;
  $("prog-x").textContent = p.x;
  $("prog-flags").textContent = p.flags;
  $("prog-vars").replaceChildren(...Object.entries(p.variables || {}).map(([n, v]) =>
    el("tr", {}, el("th", {}, `var ${n}`), el("td", {id: `prog-var-${n}`}, v ?? "-"))));
  const line = D.downloaded ? p.line : null;
  if (line !== D.currentLine) {
    const old = D.currentLine && $(`line-${D.currentLine}`);
    if (old) old.className = D.errorLines.has(D.currentLine) ? "error" : "";
    D.currentLine = line;
    const cur = line && $(`line-${line}`);
    if (cur) cur.className = "current";
  }
}

function setupEditor() {
  const t = $("editor");
  t.value = localStorage.getItem(SOURCE_KEY) || EXAMPLE;
  t.addEventListener("input", () => {
    localStorage.setItem(SOURCE_KEY, t.value);
    D.downloaded = false;
    if (editorLines() !== $("editor-gutter").childElementCount) renderGutter();
  });
  t.addEventListener("scroll", syncScroll);
  t.addEventListener("keydown", ev => {  // Tab indents instead of leaving the editor
    if (ev.key !== "Tab" || ev.shiftKey) return;
    ev.preventDefault();
    const a = t.selectionStart;
    t.setRangeText("    ", a, t.selectionEnd, "end");
    t.dispatchEvent(new Event("input"));
  });
  $("btn-assemble").addEventListener("click", () => assembleOnly(false));
  $("btn-download").addEventListener("click", () => assembleOnly(true));
  $("btn-run").addEventListener("click", () => programAction("run"));
  $("btn-stop").addEventListener("click", () => programAction("stop"));
  $("btn-step").addEventListener("click", () => programAction("step"));
  $("btn-reset").addEventListener("click", () => programAction("reset"));
  renderGutter();
}

// ---------------------------------------------------------------- start
async function main() {
  setupConsole();
  setupEditor();
  $("param-axis").addEventListener("change", loadParams);
  $("btn-params-reload").addEventListener("click", loadParams);
  $("param-filter").addEventListener("input", renderParams);
  $("param-filter-writable").addEventListener("change", renderParams);
  try { showOverview(await api("api/overview")); } catch (e) { log(e.message, "err"); }
  try { await setupModules(); } catch (e) { log(e.message, "err"); }
  try {  // the program the dashboard downloaded before (e.g. from another tab) is what runs
    const prog = await api("api/program");
    if (prog.source) {
      $("editor").value = prog.source;
      D.downloaded = true;
      D.breakpoints = new Set((prog.state.breakpoints || []).map(a => prog.lines[a]).filter(l => l));
      renderGutter();
      showProgramState(prog.state);
    }
  } catch (e) { log(e.message, "err"); }
  connect();
  loadParams();
  requestAnimationFrame(animate);
}
main();
