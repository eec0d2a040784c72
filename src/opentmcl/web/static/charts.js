// The "charts" view (docs/dashboard-charts.md): several live charts, each of position or velocity
// (the WebSocket's samples) or of any readable axis/global parameter or input (the server's chart
// sampler, web/sampler.py), drawn with the vendored uPlot; pause/resume, zoom/pan, cursor read-out,
// CSV and PNG export.
"use strict";
(() => {
const {api, el, log} = window.OpenTMCL;
const $ = id => document.getElementById(id);
const D = window.dashboard;  // D.charts[id]: {t: [...], series: [{label, y: [...]}]}, read by the browser tests

const COLORS = ["#1565c0", "#c62828", "#2e7d32", "#ef6c00", "#6a1b9a", "#00838f", "#5d4037", "#ad1457"];
const POLL_MS = 250;          // sampler rows are fetched 4 times a second (sampled at the live rate)
const WINDOWS = [10, 30, 60, 120, 300];
// Chart height: 190 px, taller on a tall screen (two charts fill a 1080-line screen, issue 31 item 6).
const height = () => Math.max(190, Math.min(420, Math.round((window.innerHeight - 300) / 2)));
const C = {ctx: null, catalogue: null, seconds: 60, next: 1, client: null, keys: [], lastSeq: 0,
           polling: null, subscribing: null, maxSeries: 16, storeKey: `opentmcl-charts ${location.pathname}`};

// ---------------------------------------------------------------- sources
// "ws:position" / "ws:velocity": every axis from the WebSocket; "axis:N" (axes chosen), "global:B:N", "io:B:P".
function sourceInfo(source) {
  const ov = C.ctx.overview, cat = C.catalogue || {axis: [], global: [], io: []};
  const [kind, a, b] = source.split(":");
  if (kind === "ws") {  // in the axes' units (static/units.js) once they are known
    const u = window.OpenTMCL.units, axes = [...Array(ov.axes).keys()];
    const unitOf = i => (a === "position" ? u.positionUnit(i) : u.velocityUnit(i));
    const known = u && u.info, same = known && axes.every(i => unitOf(i) === unitOf(0));
    return {kind, title: a === "position" ? "actual position (AP 1)" : "actual speed (AP 3)",
            unit: known ? (same ? unitOf(0) : "each axis in its unit") : a === "position" ? "µsteps" : ov.velocity_unit, perAxis: true};
  }
  if (kind === "axis") {
    const p = cat.axis.find(q => q.number === Number(a));
    return p && {kind, number: p.number, name: p.name, title: `${p.title} (AP ${p.number})`, unit: p.unit, perAxis: true};
  }
  if (kind === "global") {
    const p = cat.global.find(q => q.bank === Number(a) && q.number === Number(b));
    return p && {kind, title: `${p.title} (GP ${p.number}, bank ${p.bank})`, name: p.name, unit: p.unit, perAxis: false};
  }
  if (kind === "io") {
    const p = cat.io.find(q => q.bank === Number(a) && q.port === Number(b));
    return p && {kind, title: `${p.name} (GIO ${p.port}, ${p.bank})`, name: p.name, unit: "", perAxis: false};
  }
  return null;
}

function seriesOf(cfg) {  // [{key, label}] of a chart; key null for WebSocket series
  const info = sourceInfo(cfg.source);
  if (!info) return [];
  if (info.kind === "ws") return (cfg.axes || []).map(a => ({key: null, axis: a, label: `axis ${a}`}));
  if (info.kind === "axis") return (cfg.axes || []).map(a => ({key: `axis:${a}:${info.number}`, axis: a, label: `axis ${a} ${info.name}`}));
  return [{key: cfg.source, axis: null, label: info.name}];
}

function sourceOptions() {
  const cat = C.catalogue, opts = [
    el("option", {value: "ws:position"}, "position (all axes, live)"), el("option", {value: "ws:velocity"}, "velocity (all axes, live)")];
  const group = (label, items) => el("optgroup", {label}, ...items);
  if (!cat) return opts;
  opts.push(group("axis parameters", cat.axis.map(p => el("option", {value: `axis:${p.number}`}, `AP ${p.number} ${p.title}`))));
  opts.push(group("global parameters", cat.global.map(p => el("option", {value: `global:${p.bank}:${p.number}`}, `GP ${p.number}, ${p.bank} ${p.title}`))));
  opts.push(group("inputs and outputs", cat.io.map(p => el("option", {value: `io:${p.bank}:${p.port}`}, `${p.name} (${p.kind})`))));
  return opts;
}

// ---------------------------------------------------------------- one chart
function plotOptions(chart, width) {
  const info = sourceInfo(chart.cfg.source) || {title: chart.cfg.source, unit: ""};
  return {
    width, height: height(),
    scales: {x: {time: false}},
    legend: {live: true},
    cursor: {drag: {x: true, y: false}},
    series: [{label: "t [s]", value: (u, v) => v === null || v === undefined ? "-" : v.toFixed(2)},
             ...chart.series.map((s, i) => ({label: s.label, stroke: COLORS[(s.axis ?? i) % COLORS.length], width: 1.5,
                                             spanGaps: false, points: {show: false}}))],
    axes: [{label: "time [s]"}, {label: info.unit ? `[${info.unit}]` : "", size: 70}],
    hooks: {setSelect: [u => { if (u.select.width > 0) chart.zoomed = true; }]},
  };
}

function build(chart) {
  const box = chart.node.querySelector(".chart-plot");
  box.replaceChildren();
  chart.t = []; chart.series = seriesOf(chart.cfg).map(s => ({...s, y: []}));
  chart.dirty = true; chart.zoomed = false;
  if (!window.uPlot) { box.append(el("div", {class: "err"}, "uPlot did not load")); return; }
  chart.plot = new window.uPlot(plotOptions(chart, plotWidth()), [chart.t, ...chart.series.map(s => s.y)], box);
  chart.plot.over.addEventListener("dblclick", () => { chart.zoomed = false; chart.dirty = true; });
  chart.plot.over.addEventListener("wheel", ev => wheel(chart, ev), {passive: false});
  chart.node.querySelector(".chart-title").textContent = (sourceInfo(chart.cfg.source) || {}).title || chart.cfg.source;
}

function wheel(chart, ev) {  // wheel: zoom the time axis around the cursor; shift+wheel: pan
  ev.preventDefault();
  const u = chart.plot, x = u.scales.x;
  if (x.min === null || x.max === null) return;
  const span = x.max - x.min, at = u.posToVal(ev.offsetX, "x");
  let min, max;
  if (ev.shiftKey || Math.abs(ev.deltaX) > Math.abs(ev.deltaY)) {
    const shift = span * 0.1 * Math.sign(ev.deltaY || ev.deltaX);
    min = x.min + shift; max = x.max + shift;
  } else {
    const f = ev.deltaY > 0 ? 1.25 : 0.8;
    min = at - (at - x.min) * f; max = at + (x.max - at) * f;
  }
  chart.zoomed = true;
  u.setScale("x", {min, max});
}

function push(chart, t, values) {
  const last = chart.t.length ? chart.t[chart.t.length - 1] : -Infinity;
  if (chart.paused || !(t > last)) return;  // time only moves forward (a row polled twice is dropped)
  if (chart.gap && t - 1e-3 > last) {  // resumed after a pause: a break, not a straight line
    chart.t.push(t - 1e-3); chart.series.forEach(s => s.y.push(null));
  }
  chart.gap = false;
  chart.t.push(t);
  chart.series.forEach((s, i) => s.y.push(values[i] ?? null));
  const cut = t - C.seconds;
  let drop = 0;
  while (drop < chart.t.length && chart.t[drop] < cut) drop++;
  if (drop) { chart.t.splice(0, drop); chart.series.forEach(s => s.y.splice(0, drop)); }
  chart.dirty = true;
}

function togglePause(chart) {
  chart.paused = !chart.paused;
  if (!chart.paused) chart.gap = true;
  const b = chart.node.querySelector(".btn-pause");
  b.textContent = chart.paused ? "Resume" : "Pause";
  chart.node.classList.toggle("paused", chart.paused);
}

function saveBlob(blob, name) {
  const a = el("a", {href: URL.createObjectURL(blob), download: name});
  document.body.append(a); a.click(); a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 10000);
}

function fileName(chart, ext) { return `opentmcl-${chart.cfg.source.replace(/:/g, "-")}.${ext}`; }

function csv(chart) {
  const head = ["t_s", ...chart.series.map(s => s.label.replace(/[",\n]/g, " "))].join(",");
  const rows = chart.t.map((t, k) => [t, ...chart.series.map(s => s.y[k] ?? "")].join(","));
  return [head, ...rows].join("\n") + "\n";
}

function png(chart) {
  const src = chart.plot.ctx.canvas, title = chart.node.querySelector(".chart-title").textContent;
  const out = document.createElement("canvas");
  out.width = src.width; out.height = src.height + 28;
  const g = out.getContext("2d");
  g.fillStyle = "#fff"; g.fillRect(0, 0, out.width, out.height);
  g.fillStyle = "#1d232c"; g.font = "16px system-ui, sans-serif"; g.fillText(title, 10, 20);
  g.drawImage(src, 0, 28);
  out.toBlob(b => saveBlob(b, fileName(chart, "png")), "image/png");
}

function axesPicker(chart) {
  const box = chart.node.querySelector(".chart-axes");
  box.replaceChildren();
  const info = sourceInfo(chart.cfg.source);
  if (!info || !info.perAxis) return;
  for (let a = 0; a < C.ctx.overview.axes; a++) {
    const cb = el("input", {type: "checkbox", class: "chart-axis", "data-axis": a});
    cb.checked = chart.cfg.axes.includes(a);
    cb.addEventListener("change", () => {
      const axes = cb.checked ? [...chart.cfg.axes, a].sort() : chart.cfg.axes.filter(x => x !== a);
      if (!setConfig(chart, {...chart.cfg, axes})) cb.checked = !cb.checked;
    });
    box.append(el("label", {style: `color:${COLORS[a % COLORS.length]}`}, cb, ` ${a}`));
  }
}

function setConfig(chart, cfg) {
  const old = chart.cfg;
  chart.cfg = cfg;
  if (sampledCount() > C.maxSeries) {
    chart.cfg = old;
    log(`at most ${C.maxSeries} sampled series at once (web/sampler.py); remove one first`, "err");
    return false;
  }
  build(chart); axesPicker(chart); save(); resubscribe();
  return true;
}

function addChart(cfg, id) {
  id = id || `c${C.next++}`;
  const node = el("div", {class: "chart-card", id: `chart-${id}`});
  const chart = {id, cfg, node, t: [], series: [], paused: false, zoomed: false, dirty: true};
  const select = el("select", {class: "chart-source", title: "what this chart shows"}, ...sourceOptions());
  select.value = cfg.source;
  select.addEventListener("change", () => {
    const info = sourceInfo(select.value);
    if (!setConfig(chart, {source: select.value, axes: info && info.perAxis ? (chart.cfg.axes.length ? chart.cfg.axes : [0]) : []})) {
      select.value = chart.cfg.source;
    }
  });
  node.append(
    el("div", {class: "toolbar"}, el("span", {class: "chart-title"}, ""), select, el("span", {class: "chart-axes", title: "axes"}),
      el("span", {class: "sep"}),
      el("button", {class: "btn-pause", onclick: () => togglePause(chart)}, "Pause"),
      el("button", {class: "btn-live", title: "back to the live window (double-click the plot does the same)",
                    onclick: () => { chart.zoomed = false; chart.dirty = true; }}, "Live"),
      el("button", {class: "btn-csv", onclick: () => saveBlob(new Blob([csv(chart)], {type: "text/csv"}), fileName(chart, "csv"))}, "CSV"),
      el("button", {class: "btn-png", onclick: () => png(chart)}, "PNG"),
      el("button", {class: "btn-remove", title: "remove this chart", onclick: () => removeChart(chart)}, "✕")),
    el("div", {class: "chart-plot"}));
  $("chart-list").append(node);
  D.charts[id] = chart;
  if (sampledCount() > C.maxSeries) { node.remove(); delete D.charts[id]; log(`at most ${C.maxSeries} sampled series at once`, "err"); return null; }
  build(chart); axesPicker(chart);
  return chart;
}

function removeChart(chart) {
  chart.node.remove();
  if (chart.plot) chart.plot.destroy();
  delete D.charts[chart.id];
  save(); resubscribe();
}

// ---------------------------------------------------------------- feeds
function onSamples(samples) {  // the WebSocket: position (p) and velocity (v) of every axis
  for (const chart of Object.values(D.charts)) {
    const [kind, which] = chart.cfg.source.split(":");
    if (kind !== "ws") continue;
    const field = which === "position" ? "p" : "v", u = window.OpenTMCL.units;
    const conv = !u || !u.info ? (_axis, v) => v : which === "position" ? u.position : u.velocity;
    for (const s of samples) push(chart, s.t, chart.series.map(x => conv(x.axis, s[field][x.axis])));
  }
}

function sampledKeys() {
  const keys = new Set();
  for (const chart of Object.values(D.charts)) for (const s of seriesOf(chart.cfg)) if (s.key) keys.add(s.key);
  return [...keys];
}

function sampledCount() { return sampledKeys().length; }

async function resubscribe() {
  const keys = sampledKeys();
  if (!keys.length) { stopPolling(); C.keys = []; return; }
  const series = keys.map(k => { const [kind, index, number] = k.split(":"); return {kind, index: Number(index), number: Number(number)}; });
  const mine = C.subscribing = {};
  try {
    const r = await api("api/charts/subscribe", {client: C.client, series});
    if (C.subscribing !== mine) return;  // a newer subscription is under way
    C.client = r.client; C.keys = r.series;  // row numbers are global: C.lastSeq stays valid
    startPolling();
  } catch (e) { log(`charts: ${e.message}`, "err"); }
}

async function poll() {
  if (!C.client || C.inFlight) return;
  C.inFlight = true;
  try {
    const r = await api(`api/charts/samples?client=${encodeURIComponent(C.client)}&since=${C.lastSeq}`);
    const column = new Map(r.series.map((k, i) => [k, i + 2]));
    for (const row of r.rows) {
      C.lastSeq = Math.max(C.lastSeq, row[0]);
      for (const chart of Object.values(D.charts)) {
        if (chart.cfg.source.startsWith("ws:") || !chart.series.every(s => column.has(s.key))) continue;  // rows of an older subscription
        push(chart, row[1], chart.series.map(s => column.has(s.key) ? row[column.get(s.key)] : null));
      }
    }
    C.pollError = null;
  } catch (e) {
    if (/subscribe again/.test(e.message)) { C.client = null; C.lastSeq = 0; resubscribe(); }  // expired, or a new server
    else if (e.message !== C.pollError) log(`charts: ${e.message}`, "err");  // once, not at every poll
    C.pollError = e.message;
  } finally { C.inFlight = false; }
}

function startPolling() { if (!C.polling) C.polling = setInterval(poll, POLL_MS); }
function stopPolling() { if (C.polling) clearInterval(C.polling); C.polling = null; }

// ---------------------------------------------------------------- drawing
function plotWidth() { const list = $("chart-list"); return Math.max(300, (list && list.clientWidth || 900) - 4); }

function draw() {
  if (C.ctx && C.ctx.isVisible()) {
    for (const chart of Object.values(D.charts)) {
      if (!chart.dirty || !chart.plot) continue;
      chart.dirty = false;
      // following: rescale to the newest window; zoomed: keep the user's time axis
      chart.plot.setData([chart.t, ...chart.series.map(s => s.y)], !chart.zoomed);
    }
  }
  requestAnimationFrame(draw);
}

function resize() {
  const w = plotWidth();
  for (const chart of Object.values(D.charts)) if (chart.plot) { chart.plot.setSize({width: w, height: height()}); chart.dirty = true; }
}

// ---------------------------------------------------------------- configuration kept per module page
function save() {
  const list = Object.values(D.charts).map(c => ({source: c.cfg.source, axes: c.cfg.axes}));
  try { localStorage.setItem(C.storeKey, JSON.stringify({charts: list, seconds: C.seconds})); } catch (_) { /* private mode */ }
}

function restore(axes) {
  const all = Array.from({length: axes}, (_, i) => i);
  const defaults = {charts: [{source: "ws:position", axes: all}, {source: "ws:velocity", axes: all}], seconds: 60};
  let saved = null;
  try { saved = JSON.parse(localStorage.getItem(C.storeKey) || "null"); } catch (_) { saved = null; }
  const cfg = saved && Array.isArray(saved.charts) ? saved : defaults;
  if (WINDOWS.includes(cfg.seconds)) C.seconds = cfg.seconds;
  return cfg.charts.filter(c => c && typeof c.source === "string" && sourceInfo(c.source))
    .map(c => ({source: c.source, axes: Array.isArray(c.axes) ? c.axes.filter(a => Number.isInteger(a) && a >= 0 && a < axes) : []}));
}

const MARKUP = `
    <h2>Live charts</h2>
    <div class="toolbar">
      <button id="btn-chart-add" title="add a chart; choose what it shows in its own toolbar">Add chart</button>
      <label>window <select id="chart-window"></select></label>
      <span class="hint">drag: zoom · wheel: zoom · shift+wheel: pan · double-click or Live: follow · legend: values at the cursor</span>
    </div>
    <div id="chart-list"></div>`;

OpenTMCL.registerView("charts", {
  mount(root, ctx) {
    mountCharts(root, ctx).catch(e => log(`charts: ${e.message}`, "err"));
  },
  show() { resize(); },
});

async function mountCharts(root, ctx) {
    C.ctx = ctx;
    root.innerHTML = MARKUP;
    const ov = ctx.overview;
    if (!ov) return;
    C.seconds = ov.history_seconds || 60;
    try {
      C.catalogue = await api("api/charts/series");
      C.maxSeries = C.catalogue.max_series || C.maxSeries;
    } catch (e) { log(`charts: ${e.message}`, "err"); }
    const configs = restore(ov.axes);
    const win = $("chart-window");
    win.replaceChildren(...WINDOWS.map(s => el("option", {value: s}, `${s} s`)));
    win.value = String(C.seconds);
    win.addEventListener("change", () => { C.seconds = Number(win.value); save(); });
    configs.forEach((cfg, i) => addChart(cfg, i === 0 && cfg.source === "ws:position" ? "position"
                                             : i === 1 && cfg.source === "ws:velocity" ? "velocity" : undefined));
    $("btn-chart-add").addEventListener("click", () => {
      const first = sourceInfo("axis:206") ? "axis:206" : "ws:position";  // the load value when the module has it
      const chart = addChart({source: first, axes: [0]}) || addChart({source: "ws:position", axes: [0]});
      if (chart) {
        save(); resubscribe();
        // a new chart below the fold comes into view (issue 31 item 6), once uPlot has laid out its legend
        requestAnimationFrame(() => requestAnimationFrame(() => chart.node.scrollIntoView({block: "nearest"})));
      }
    });
    ctx.onSamples(onSamples);
    const u = window.OpenTMCL.units;  // a new unit: the live charts start again in it
    if (u) u.onChange(() => { for (const chart of Object.values(D.charts)) if (chart.cfg.source.startsWith("ws:")) build(chart); });
    window.addEventListener("resize", resize);
    resubscribe();
    requestAnimationFrame(draw);
}
})();
