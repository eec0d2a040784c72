// A small scatter chart on a canvas (one value against another, e.g. the stallGuard2 load value
// against velocity), for the tuning tools: axes with ticks, the points (the newest darkest), and
// marker lines (a threshold, a speed limit). No library: uPlot draws time series.
"use strict";
(() => {
function ticks(lo, hi, count = 5) {
  const span = hi - lo || 1, raw = span / count, mag = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 5, 10].map(m => m * mag).find(s => span / s <= count) || raw;
  const out = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) out.push(Number(v.toPrecision(10)));
  return out;
}

function xyChart(canvas, opts) {
  const g = canvas.getContext("2d");
  const state = {points: [], lines: [], xMax: 1, ...opts};
  const pad = {l: 58, r: 12, t: 10, b: 36};

  function draw() {
    const dpr = window.devicePixelRatio || 1, w = canvas.clientWidth || 400, h = canvas.clientHeight || 220;
    if (canvas.width !== Math.round(w * dpr)) { canvas.width = Math.round(w * dpr); canvas.height = Math.round(h * dpr); }
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    g.clearRect(0, 0, w, h);
    const xs = state.points.map(p => p.x).concat(state.lines.filter(l => l.x !== undefined).map(l => l.x));
    const xMin = Math.min(0, ...xs), xMax = Math.max(state.xMax, ...xs) * 1.05 || 1;
    const yMin = state.yMin, yMax = state.yMax;
    const X = v => pad.l + (v - xMin) / (xMax - xMin) * (w - pad.l - pad.r);
    const Y = v => h - pad.b - (v - yMin) / (yMax - yMin) * (h - pad.t - pad.b);
    g.strokeStyle = "#d8dce3"; g.fillStyle = "#687385"; g.font = "11px system-ui, sans-serif"; g.lineWidth = 1;
    for (const v of ticks(xMin, xMax)) {
      g.beginPath(); g.moveTo(X(v), pad.t); g.lineTo(X(v), h - pad.b); g.stroke();
      g.fillText(String(v), X(v) - 10, h - pad.b + 14);
    }
    g.textAlign = "right";
    for (const v of ticks(yMin, yMax)) {
      g.beginPath(); g.moveTo(pad.l, Y(v)); g.lineTo(w - pad.r, Y(v)); g.stroke();
      g.fillText(String(v), pad.l - 4, Y(v) + 4);
    }
    g.textAlign = "left";
    g.fillStyle = "#1d232c";
    g.fillText(state.xLabel, pad.l + 4, h - 4);
    g.save(); g.translate(11, h - pad.b); g.rotate(-Math.PI / 2); g.fillText(state.yLabel, 0, 0); g.restore();
    for (const l of state.lines) {
      g.strokeStyle = l.color; g.setLineDash([5, 4]); g.beginPath();
      if (l.y !== undefined) { g.moveTo(pad.l, Y(l.y)); g.lineTo(w - pad.r, Y(l.y)); }
      else { g.moveTo(X(l.x), pad.t); g.lineTo(X(l.x), h - pad.b); }
      g.stroke(); g.setLineDash([]);
      g.fillStyle = l.color;
      if (l.y !== undefined) g.fillText(l.label, w - pad.r - g.measureText(l.label).width - 2, Y(l.y) - 4);
      else g.fillText(l.label, X(l.x) + 4, pad.t + 12);
    }
    const n = state.points.length;
    state.points.forEach((p, k) => {
      g.fillStyle = `rgba(21, 101, 192, ${0.15 + 0.85 * (k + 1) / n})`;
      g.beginPath(); g.arc(X(p.x), Y(Math.max(yMin, Math.min(yMax, p.y))), 2.5, 0, 2 * Math.PI); g.fill();
    });
  }

  return {
    set(points, changes = {}) { state.points = points; Object.assign(state, changes); draw(); },
    draw,
    get state() { return state; },
  };
}

window.OpenTMCL.xyChart = xyChart;
})();
