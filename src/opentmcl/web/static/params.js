// The "parameters" view (docs/dashboard-parameters.md): axis and global tables that refresh while
// visible, highlight changed values, edit in place within the manual's range, store/restore to
// EEPROM, and export/import parameter sets with a diff that applies only on confirmation.
// Every row carries its own axis (or bank) and module, and a write goes there and nowhere else:
// only when that is the axis and module shown. A table being replaced by another axis's is
// read-only until the new values arrive (issue 28: a value typed meanwhile went to the old axis).
"use strict";
(() => {
const {api, el, log} = window.OpenTMCL;
const $ = id => document.getElementById(id);
const REFRESH_MS = 500;      // 2 Hz, one batched request (api/params/values/AXIS)
const FLASH_MS = 1500;       // how long a changed value stays highlighted
const BANK_TITLES = {0: "bank 0: global parameters", 2: "bank 2: user variables", 3: "bank 3: interrupt configuration"};
const P = {axisParams: null, globalParams: null, values: null, timer: null, ctx: null, busy: false,
           pendingFile: null, axis: null, loading: false, loadSeq: 0};
window.dashboard.params = P;  // for the browser tests and the curious

const MARKUP = `
    <h2>Parameters</h2>
    <div class="toolbar">
      <label>Axis <select id="param-axis"></select></label>
      <button id="btn-params-reload">Reload</button>
      <label title="read every value twice a second while this view is shown"><input type="checkbox" id="param-live" checked> live</label>
      <label><input type="checkbox" id="param-filter-writable"> writable only</label>
      <input id="param-filter" placeholder="filter by name">
      <span class="sep"></span>
      <button id="btn-params-export-json" title="download the parameter set as JSON">Export JSON</button>
      <button id="btn-params-export-toml" title="download the parameter set as TOML">Export TOML</button>
      <label class="file-button">Import… <input type="file" id="param-import" accept=".json,.toml,application/json,application/toml,text/plain"></label>
    </div>
    <div id="param-import-panel" hidden></div>
    <h3 id="param-axis-title">Axis parameters</h3>
    <table id="param-axis-table" class="params"></table>
    <div id="param-global-tables"></div>`;

const axisNow = () => Number($("param-axis").value || 0);
const moduleShown = () => (P.ctx && P.ctx.overview ? P.ctx.overview.address : null);
const mnemonic = (kind, store, restore) => kind === "axis" ? (restore ? "RSAP" : store ? "STAP" : "SAP")
                                                            : (restore ? "RSGP" : store ? "STGP" : "SGP");
const excludedText = p => (p.excluded || []).length ? ` except ${p.excluded.join(", ")}` : "";  // e.g. PD86-1180 7.2 AP210
const rangeText = p => p.values.length ? p.values.join(", ") : `${p.min} … ${p.max}${excludedText(p)}`;

// A value the manual allows for parameter p (profile data: min/max minus excluded, or the list of values).
function checkValue(p, text) {
  const t = String(text).trim();
  if (!/^[-+]?(0x[0-9a-f]+|\d+)$/i.test(t)) return {error: `"${t}" is not an integer`};
  const neg = t.startsWith("-"), body = t.replace(/^[-+]/, "");
  const v = (neg ? -1 : 1) * Number(body.toLowerCase().startsWith("0x") ? parseInt(body, 16) : body);
  if (!Number.isSafeInteger(v)) return {error: `${t} is too large`};
  const ok = p.values.length ? p.values.includes(v) : v >= p.min && v <= p.max && !(p.excluded || []).includes(v);
  if (!ok) return {error: `${p.title} takes ${rangeText(p)}${p.unit ? " [" + p.unit + "]" : ""}, not ${v}`};
  return {value: v};
}

// A value in the axis's physical units (static/units.js): velocities, accelerations and positions in
// the unit chosen for the axis, currents in mA RMS; "" for everything else.
const VELOCITY_UNITS = new Set(["pps", "int_velocity"]), ACCEL_UNITS = new Set(["pps^2", "int_acceleration"]);
const CURRENTS = new Set([6, 7, 183]);
function physical(kind, p, index, value) {
  const u = window.OpenTMCL.units;
  if (kind !== "axis" || !u || !u.info || value === null || value === undefined) return "";
  const f = x => (x === null || x === undefined ? "" : u.fmt(x, 5));
  if (VELOCITY_UNITS.has(p.unit)) return `${f(u.velocity(index, value))} ${u.velocityUnit(index)}`;
  if (ACCEL_UNITS.has(p.unit)) return `${f(u.accel(index, value))} ${u.accelUnit(index)}`;
  if (p.unit === "µsteps" && p.number !== 209) return `${f(u.position(index, value))} ${u.positionUnit(index)}`;
  if (u.currentScale() && CURRENTS.has(p.number)) return `${Math.round(u.currentMa(value))} mA`;
  if (u.currentScale() && p.number === 180) return `${Math.round(u.scaleMa(value))} mA`;
  return "";
}

function cellId(kind, p) { return kind === "axis" ? `param-axis-${p.number}` : `param-global-${p.bank}-${p.number}`; }

function valueCell(kind, p, index, module) {
  const id = cellId(kind, p);
  if (!p.writable) return el("td", {class: "num"}, el("span", {id, class: "value"}, p.value ?? "-"));
  const input = el("input", {id, value: p.value ?? "", "data-number": p.number, title: `${rangeText(p)} ${p.unit}`.trim(),
                             "data-kind": kind, "data-index": index, "data-module": module,
                             spellcheck: "false", autocomplete: "off"});
  if (kind === "axis" && P.loading) input.disabled = true;
  input.addEventListener("input", () => { input.dataset.dirty = "1"; input.classList.remove("saved", "failed"); });
  input.addEventListener("blur", () => {  // leaving without Enter drops the edit; live values come back
    if (input.dataset.dirty && !input.classList.contains("failed")) { delete input.dataset.dirty; refresh(); }
  });
  input.addEventListener("keydown", ev => { if (ev.key === "Enter") writeValue(kind, p, input); });
  return el("td", {class: "num"}, input);
}

// Why a write from a row of (kind, index, module) must not be sent now, or "" when it may: the row
// must be of the axis and module shown, and its table not being replaced.
function notShown(kind, index, module) {
  if (module !== moduleShown()) return `this row is of module ${module}, the page shows module ${moduleShown()}`;
  if (kind !== "axis") return "";
  if (P.loading || index !== P.axis) return `axis ${axisNow()} is being read; nothing written to axis ${index}`;
  if (index !== axisNow()) return `this row is of axis ${index}, axis ${axisNow()} is chosen`;
  return "";
}

async function writeValue(kind, p, input) {
  input.classList.remove("saved", "failed");
  const index = Number(input.dataset.index), module = Number(input.dataset.module);
  const refused = notShown(kind, index, module);
  if (refused) {
    input.classList.add("failed"); input.title = refused; log(refused, "err");
    return;
  }
  const checked = checkValue(p, input.value);
  if (checked.error) {
    input.classList.add("failed"); input.title = checked.error; log(checked.error, "err");
    return;
  }
  log(`> ${mnemonic(kind)} ${p.number}, ${index}, ${checked.value}`, "req");
  const body = kind === "axis" ? {axis: index, number: p.number, value: checked.value, module}
                               : {bank: index, number: p.number, value: checked.value, module};
  try {
    const r = await api(`api/params/${kind}`, body);
    delete input.dataset.dirty;
    input.value = r.value; input.classList.add("saved"); input.title = `${rangeText(p)} ${p.unit}`.trim();
    remember(kind, p, index, r.value);
    if (kind === "axis") showPhysical(p.number, r.value);
    const u = window.OpenTMCL.units;  // the factors of the units depend on these (web/units.py)
    if (kind === "axis" && u && [140, 153, 154, 202, 255].includes(p.number)) u.reload().catch(e => log(e.message, "err"));
    log(`  ${p.name} = ${r.value}`, "ok");
  } catch (e) { input.classList.add("failed"); input.title = e.message; log(`  ${e.message}`, "err"); }
}

function remember(kind, p, index, value) {
  if (!P.values) return;
  if (kind === "axis") { if (index === P.axis && !P.loading) P.values.axis[String(p.number)] = value; }
  else P.values.global[`${index}:${p.number}`] = value;
}

function paramRows(table, params, kind, index) {
  const module = moduleShown();
  table.dataset.kind = kind; table.dataset.index = index; table.dataset.module = module;
  const filter = $("param-filter").value.trim().toLowerCase();
  const writableOnly = $("param-filter-writable").checked;
  const rows = [el("tr", {}, ...["#", "name", "value", "unit", "physical", "range", "access", "EEPROM"].map(h => el("th", {}, h)))];
  for (const p of params) {
    if (writableOnly && !p.writable) continue;
    if (filter && !p.name.includes(filter) && !p.title.toLowerCase().includes(filter) && String(p.number) !== filter) continue;
    const buttons = el("td", {});
    const where = kind === "axis" ? index : p.bank;
    const lock = kind === "axis" && P.loading ? {disabled: ""} : {};
    if (p.can_store) buttons.append(el("button", {id: `${cellId(kind, p)}-store`, title: `${mnemonic(kind, true)} ${p.number}, ${where}`,
                                                  ...lock, onclick: () => storeParam(kind, p, where, module, false)}, "store"));
    if (p.can_restore) buttons.append(el("button", {id: `${cellId(kind, p)}-restore`, title: `${mnemonic(kind, false, true)} ${p.number}, ${where}`,
                                                    ...lock, onclick: () => storeParam(kind, p, where, module, true)}, "restore"));
    rows.push(el("tr", {class: p.writable ? "" : "ro", "data-kind": kind, "data-index": where, "data-module": module},
      el("td", {class: "num"}, `${p.number}`),
      el("td", {title: p.description || p.title}, p.title), valueCell(kind, p, where, module), el("td", {}, p.unit),
      el("td", {class: "num phys", id: `${cellId(kind, p)}-phys`}, physical(kind, p, where, valueOf(kind, p, where))),
      el("td", {}, rangeText(p)), el("td", {}, p.access), buttons));
  }
  table.replaceChildren(...rows);
}

async function storeParam(kind, p, where, module, restore) {
  const refused = notShown(kind, where, module);
  if (refused) { log(refused, "err"); return; }
  log(`> ${mnemonic(kind, !restore, restore)} ${p.number}, ${where}`, "req");
  try {
    await api("api/params/store", {kind, number: p.number, index: where, restore, module});
    log(`  ${restore ? "restored" : "stored"} ${p.name}`, "ok");
    if (restore) refresh();
  } catch (e) { log(`  ${e.message}`, "err"); }
}

// The axis table of the axis chosen (and the global tables the first time and on Reload): the
// axis table shown turns read-only at once and stays so until the values of that axis arrive (a
// later choice wins over an answer still on its way).
async function loadParams(withGlobals = false) {
  const axis = axisNow(), seq = ++P.loadSeq;
  setLoading(true, axis);
  try {
    const [a, g] = await Promise.all([api(`api/params/axis/${axis}`),
      withGlobals || !P.globalParams ? api("api/params/global") : {params: P.globalParams}]);
    if (seq !== P.loadSeq || a.axis !== axisNow()) return;  // another axis was chosen meanwhile
    P.axisParams = a.params; P.globalParams = g.params; P.axis = a.axis;
    P.values = {axis: {}, global: {}};
    for (const p of a.params) P.values.axis[String(p.number)] = p.value;
    for (const p of g.params) P.values.global[`${p.bank}:${p.number}`] = p.value;
    setLoading(false, a.axis);
    renderParams();
  } catch (e) {
    log(e.message, "err");
    if (seq === P.loadSeq && P.axis !== null) { $("param-axis").value = String(P.axis); setLoading(false, P.axis); }
  }
}

function setLoading(on, axis) {
  P.loading = on;
  const table = $("param-axis-table");
  table.classList.toggle("loading", on);
  if (on) table.dataset.loading = String(axis); else delete table.dataset.loading;
  for (const node of table.querySelectorAll("input, button")) node.disabled = on;
  $("param-axis-title").textContent = on ? `Axis parameters: reading axis ${axis} …` : `Axis parameters of axis ${axis}`;
}

function renderParams() {
  if (!P.axisParams) return;
  paramRows($("param-axis-table"), P.axisParams, "axis", P.axis);
  const banks = [...new Set(P.globalParams.map(p => p.bank))].sort((a, b) => a - b);
  $("param-global-tables").replaceChildren(...banks.flatMap(b => {
    const table = el("table", {id: `param-global-table-${b}`, class: "params"});
    paramRows(table, P.globalParams.filter(p => p.bank === b), "global", b);
    return [el("h3", {}, `Global parameters, ${BANK_TITLES[b] || "bank " + b}`), table];
  }));
}

// ---------------------------------------------------------------- live refresh
function flash(node) {
  node.classList.remove("changed");
  void node.offsetWidth;  // restart the highlight
  node.classList.add("changed");
  clearTimeout(node._flash);
  node._flash = setTimeout(() => node.classList.remove("changed"), FLASH_MS);
}

function valueOf(kind, p, index) {
  if (!P.values) return p.value;
  return kind === "axis" ? P.values.axis[String(p.number)] : P.values.global[`${index}:${p.number}`];
}

function showPhysical(number, value) {
  const node = $(`param-axis-${number}-phys`), p = (P.axisParams || []).find(q => q.number === Number(number));
  if (node && p) node.textContent = physical("axis", p, P.axis, value);
}

function showValue(id, value) {
  const node = $(id);
  if (!node) return;
  const text = value === null || value === undefined ? "-" : String(value);
  if (node.tagName === "INPUT") {
    if (node.dataset.dirty || document.activeElement === node) return;  // never overwrite an edit
    if (node.value !== text) { node.value = text; flash(node); }
  } else if (node.textContent !== text) { node.textContent = text; flash(node); }
}

async function refresh() {
  if (P.busy || !P.axisParams || P.loading) return;
  P.busy = true;
  const axis = P.axis;
  try {
    const r = await api(`api/params/values/${axis}`);
    if (r.axis !== P.axis || P.loading) return;  // another axis is being read meanwhile
    for (const [n, v] of Object.entries(r.values.axis)) { showValue(`param-axis-${n}`, v); showPhysical(n, v); }
    for (const [k, v] of Object.entries(r.values.global)) showValue(`param-global-${k.replace(":", "-")}`, v);
    P.values = r.values;
  } catch (e) { log(e.message, "err"); }
  finally { P.busy = false; }
}

function startLive() {
  stopLive();
  if (!$("param-live").checked || !P.ctx || !P.ctx.isVisible()) return;
  P.timer = setInterval(refresh, REFRESH_MS);
}

function stopLive() { if (P.timer) clearInterval(P.timer); P.timer = null; }

// ---------------------------------------------------------------- export and import
function download(format) {
  log(`export ${format.toUpperCase()}: GAP/GGP of every parameter of the set`, "req");
  const a = el("a", {href: `api/params/export?format=${format}`, download: ""});
  document.body.append(a); a.click(); a.remove();
}

function changeRows(changes) {
  const head = el("tr", {}, ...["", "#", "name", "current", "file"].map(h => el("th", {}, h)));
  return [head, ...changes.map(c => el("tr", {},
    el("td", {}, c.kind === "axis" ? `axis ${c.index}` : `bank ${c.index}`), el("td", {class: "num"}, c.number),
    el("td", {}, c.name), el("td", {class: "num"}, c.current ?? "-"), el("td", {class: "num new"}, c.value)))];
}

function showPanel(...kids) {
  const panel = $("param-import-panel");
  panel.replaceChildren(...kids);
  panel.hidden = kids.length === 0;
}

function refuse(message, problems) {
  showPanel(el("div", {class: "import-error", id: "param-import-error"}, `Import refused, nothing applied: ${message}`),
    ...(problems && problems.length > 1 ? [el("ul", {}, ...problems.slice(0, 20).map(p => el("li", {}, p)))] : []),
    el("button", {id: "btn-import-close", onclick: () => showPanel()}, "Close"));
  log(`import refused: ${message}`, "err");
}

async function postFile(path, text) {
  const r = await fetch(path, {method: "POST", headers: {"Content-Type": "application/json", "X-OpenTMCL": "1"},
                               body: JSON.stringify({text})});
  let data = {};
  try { data = await r.json(); } catch (_) { /* not JSON */ }
  return {ok: r.ok, data, status: r.status};
}

async function importFile(file) {
  if (!file) return;
  const text = await file.text();
  const r = await postFile("api/params/diff", text);
  if (!r.ok) { refuse(r.data.error || `HTTP ${r.status}`, r.data.problems); return; }
  const d = r.data;
  P.pendingFile = text;
  const warn = (d.warnings || []).map(w => el("div", {class: "hint"}, w));
  if (!d.changes.length) {
    showPanel(el("div", {id: "param-import-summary"}, `${file.name}: ${d.entries} values, all equal to the module's; nothing to apply.`),
              ...warn, el("button", {id: "btn-import-close", onclick: () => showPanel()}, "Close"));
    return;
  }
  showPanel(el("div", {id: "param-import-summary"}, `${file.name} (${d.module}, firmware ${d.firmware || "?"}): ` +
                                                     `${d.changes.length} of ${d.entries} values differ`),
    ...warn, el("table", {class: "params", id: "param-import-diff"}, ...changeRows(d.changes)),
    el("div", {class: "toolbar"},
      el("button", {id: "btn-import-apply", class: "primary", onclick: () => applyFile()}, `Apply ${d.changes.length} change(s)`),
      el("button", {id: "btn-import-cancel", onclick: () => { P.pendingFile = null; showPanel(); log("import cancelled"); }}, "Cancel")));
}

async function applyFile() {
  const text = P.pendingFile;
  if (text === null) return;
  P.pendingFile = null;
  const r = await postFile("api/params/apply", text);
  if (!r.ok) { refuse(r.data.error || `HTTP ${r.status}`, r.data.problems); return; }
  for (const c of r.data.changes) {
    log(`> ${mnemonic(c.kind)} ${c.number}, ${c.index}, ${c.value}`, "req");
  }
  const u = window.OpenTMCL.units, kept = Object.keys(r.data.units || {});
  if (kept.length) log(`  unit settings of axis ${kept.join(", ")} taken from the file`, "ok");
  if (u) u.reload().catch(e => log(e.message, "err"));
  showPanel(el("div", {id: "param-import-summary", class: "ok"}, `applied ${r.data.applied} change(s)`),
            el("button", {id: "btn-import-close", onclick: () => showPanel()}, "Close"));
  log(`  applied ${r.data.applied} change(s)`, "ok");
  refresh();
}

OpenTMCL.registerView("parameters", {
  mount(root, ctx) {
    P.ctx = ctx;
    root.innerHTML = MARKUP;
    const sel = $("param-axis");
    for (let i = 0; i < (ctx.overview ? ctx.overview.axes : 0); i++) sel.append(el("option", {value: i}, `${i}`));
    sel.addEventListener("change", () => loadParams());
    $("btn-params-reload").addEventListener("click", () => loadParams(true));
    $("param-live").addEventListener("change", startLive);
    $("param-filter").addEventListener("input", renderParams);
    $("param-filter-writable").addEventListener("change", renderParams);
    $("btn-params-export-json").addEventListener("click", () => download("json"));
    $("btn-params-export-toml").addEventListener("click", () => download("toml"));
    $("param-import").addEventListener("change", ev => { importFile(ev.target.files[0]); ev.target.value = ""; });
    loadParams(true);
    const u = window.OpenTMCL.units;
    if (u) u.onChange(() => renderParams());
  },
  show() { if (P.axisParams) refresh(); startLive(); },
  hide() { stopLive(); },
});
})();
