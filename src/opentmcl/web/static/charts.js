// The "charts" view: live position and velocity charts (moved from app.js and chart.js as-is).
"use strict";
(() => {
const {el} = window.OpenTMCL;
const $ = id => document.getElementById(id);
const D = window.dashboard;  // D.charts: read by the browser tests

const CHART_COLORS = ["#1565c0", "#c62828", "#2e7d32", "#ef6c00", "#6a1b9a", "#00838f"];

class LiveChart {
  constructor(canvas, seconds) {
    this.canvas = canvas;
    this.seconds = seconds;
    this.series = [];   // per axis: {t: [], y: []}
    this.visible = [];
    this.dirty = true;
  }
  setAxes(n) {
    this.series = Array.from({length: n}, () => ({t: [], y: []}));
    this.visible = Array.from({length: n}, () => true);
  }
  push(axis, t, y) {
    const s = this.series[axis];
    if (!s || y === null || y === undefined) return;
    s.t.push(t); s.y.push(y);
    const cut = t - this.seconds;
    let drop = 0;
    while (drop < s.t.length && s.t[drop] < cut) drop++;
    if (drop > 0) { s.t.splice(0, drop); s.y.splice(0, drop); }
    this.dirty = true;
  }
  draw() {
    if (!this.dirty) return;
    this.dirty = false;
    const c = this.canvas, dpr = window.devicePixelRatio || 1;
    const w = c.clientWidth || c.width, h = c.clientHeight || c.height;
    if (c.width !== Math.round(w * dpr)) { c.width = Math.round(w * dpr); c.height = Math.round(h * dpr); }
    const g = c.getContext("2d");
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    g.clearRect(0, 0, w, h);
    let tmax = -Infinity, ymin = Infinity, ymax = -Infinity;
    this.series.forEach((s, i) => {
      if (!this.visible[i] || !s.t.length) return;
      tmax = Math.max(tmax, s.t[s.t.length - 1]);
      for (const y of s.y) { if (y < ymin) ymin = y; if (y > ymax) ymax = y; }
    });
    const left = 70, right = 10, top = 8, bottom = 22;
    const pw = w - left - right, ph = h - top - bottom;
    g.font = "11px system-ui, sans-serif"; g.fillStyle = "#687385"; g.strokeStyle = "#e3e6eb"; g.lineWidth = 1;
    if (!isFinite(tmax)) { g.fillText("no data yet", left + 8, top + 16); return; }
    if (ymin === ymax) { ymin -= 1; ymax += 1; }
    const pad = (ymax - ymin) * 0.05; ymin -= pad; ymax += pad;
    const t0 = Math.max(0, tmax - this.seconds), t1 = Math.max(tmax, t0 + 1);
    const X = t => left + (t - t0) / (t1 - t0) * pw, Y = y => top + (ymax - y) / (ymax - ymin) * ph;
    // grid and labels
    const ystep = niceStep((ymax - ymin) / 4);
    g.textAlign = "right"; g.textBaseline = "middle";
    for (let y = Math.ceil(ymin / ystep) * ystep; y <= ymax; y += ystep) {
      g.beginPath(); g.moveTo(left, Y(y)); g.lineTo(left + pw, Y(y)); g.stroke();
      g.fillText(formatNumber(y), left - 4, Y(y));
    }
    const tstep = niceStep((t1 - t0) / 6);
    g.textAlign = "center"; g.textBaseline = "top";
    for (let t = Math.ceil(t0 / tstep) * tstep; t <= t1; t += tstep) {
      g.beginPath(); g.moveTo(X(t), top); g.lineTo(X(t), top + ph); g.stroke();
      g.fillText(formatNumber(t) + " s", X(t), top + ph + 4);
    }
    g.strokeStyle = "#b0b7c3"; g.strokeRect(left, top, pw, ph);
    this.series.forEach((s, i) => {
      if (!this.visible[i] || s.t.length < 1) return;
      g.strokeStyle = CHART_COLORS[i % CHART_COLORS.length]; g.lineWidth = 1.5;
      g.beginPath();
      for (let k = 0; k < s.t.length; k++) {
        const x = X(s.t[k]), y = Y(s.y[k]);
        if (k === 0) g.moveTo(x, y); else g.lineTo(x, y);
      }
      g.stroke();
    });
  }
}

function niceStep(raw) {
  if (!(raw > 0)) return 1;
  const p = Math.pow(10, Math.floor(Math.log10(raw))), f = raw / p;
  return (f < 1.5 ? 1 : f < 3.5 ? 2 : f < 7.5 ? 5 : 10) * p;
}

function formatNumber(v) {
  const a = Math.abs(v);
  if (a >= 1e6) return (v / 1e6).toFixed(a >= 1e7 ? 0 : 1) + "M";
  if (a >= 1e4) return (v / 1e3).toFixed(0) + "k";
  return Number.isInteger(v) ? String(v) : v.toFixed(a < 1 ? 2 : 1);
}

const MARKUP = `
    <h2>Live charts <small>(last 60 s)</small></h2>
    <div id="chart-axes"></div>
    <div class="chart"><div class="chart-title">position [µsteps]</div><canvas id="chart-position" width="900" height="200"></canvas></div>
    <div class="chart"><div class="chart-title">velocity [<span id="vel-unit">pps</span>]</div><canvas id="chart-velocity" width="900" height="200"></canvas></div>`;

function onSamples(samples) {
  if (!D.charts.position) return;
  for (const s of samples) {
    s.p.forEach((v, i) => D.charts.position.push(i, s.t, v));
    s.v.forEach((v, i) => D.charts.velocity.push(i, s.t, v));
  }
}

function animate() {
  for (const c of Object.values(D.charts)) c.draw();
  requestAnimationFrame(animate);
}

OpenTMCL.registerView("charts", {
  mount(root, ctx) {
    root.innerHTML = MARKUP;
    const ov = ctx.overview;
    if (!ov) return;
    const chartAxes = $("chart-axes");
    for (let i = 0; i < ov.axes; i++) {
      const cb = el("input", {type: "checkbox", checked: "", onchange: e => {
        for (const c of Object.values(D.charts)) { c.visible[i] = e.target.checked; c.dirty = true; }
      }});
      chartAxes.append(el("label", {style: `color:${CHART_COLORS[i % CHART_COLORS.length]}`}, cb, ` axis ${i}`));
    }
    $("vel-unit").textContent = ov.velocity_unit;
    for (const name of ["position", "velocity"]) {
      D.charts[name] = new LiveChart($(`chart-${name}`), ov.history_seconds || 60);
      D.charts[name].setAxes(ov.axes);
    }
    ctx.onSamples(onSamples);
    requestAnimationFrame(animate);
  },
  show() { for (const c of Object.values(D.charts)) c.dirty = true; },  // redraw at the visible size
});
})();
