// The "bus" view (docs/dashboard.md "Bus overview"): every module found on the link side by side,
// with its axes' state as its own page polls it (GET ../../api/bus: no request of its own to the
// modules), the modules a scan found that are not served yet (open one to see its axes), and STOP
// ALL across all of them.
"use strict";
(() => {
const {api, el, log} = window.OpenTMCL;
const $ = id => document.getElementById(id);
const B = {timer: null, busy: false, last: null};
window.dashboard.bus = B;

function lamp(name, on, title) {
  return el("span", {class: `lamp${on ? " on" : ""}${name === "reached" ? " reached" : ""}`, title,
                     "aria-label": `${title}: ${on ? "on" : "off"}`}, name);
}

function column(m) {
  const here = location.pathname.endsWith(`/m/${m.address}/`);
  const head = el("div", {class: "bus-head"},
    el("h3", {}, `${m.module || "(no profile)"} @${m.address}`),
    el("span", {class: "hint"}, `${m.version}${m.served ? "" : ` · found by the scan${m.baud ? ` at ${m.baud} baud` : ""}`}`),
    here ? el("span", {class: "hint"}, " · this page") :
      el("button", {id: `bus-open-${m.address}`, onclick: () => openModule(m)}, "open"));
  if (!m.served) return el("div", {class: "bus-module", id: `bus-module-${m.address}`}, head,
    el("p", {class: "hint"}, "Not served yet: open it to poll its axes. STOP ALL stops it too."));
  const rows = (m.axes || []).map((a, i) => el("tr", {id: `bus-${m.address}-axis-${i}`},
    el("td", {}, `${i}`), el("td", {class: "num", id: `bus-${m.address}-${i}-position`}, a.position ?? "-"),
    el("td", {class: "num", id: `bus-${m.address}-${i}-velocity`}, a.velocity ?? "-"),
    el("td", {}, lamp("reached", a.target_reached, "target position reached (AP 8)"), lamp("L", a.left, "left limit switch (AP 11)"),
      lamp("R", a.right, "right limit switch (AP 10)"), lamp("H", a.home, "home switch (AP 9)"))));
  return el("div", {class: "bus-module", id: `bus-module-${m.address}`}, head,
    el("p", {class: "hint"}, `${m.connected ? "connected" : "not answering"} · program ${m.program || "n/a"}`),
    el("table", {class: "params bus-axes"}, el("tr", {}, ...["axis", "position", "velocity", ""].map(h => el("th", {}, h))), ...rows));
}

async function openModule(m) {
  if (m.served) { location.assign(m.url); return; }
  try { const r = await api("../../api/scan/open", {address: m.address}); location.assign(`${r.url}#bus`); }
  catch (e) { log(e.message, "err"); }
}

async function refresh() {
  if (B.busy) return;
  B.busy = true;
  try {
    const r = await api("../../api/bus");
    B.last = r;
    $("bus-modules").replaceChildren(...r.modules.map(column));
  } catch (e) { log(`bus: ${e.message}`, "err"); }
  finally { B.busy = false; }
}

OpenTMCL.registerView("bus", {
  mount(root) {
    root.replaceChildren(
      el("h2", {}, "Modules on the link"),
      el("div", {class: "toolbar"},
        el("button", {id: "bus-stop-all", class: "stop-all", onclick: () => OpenTMCL.stopAll(),
                      title: "program stop (128) and MST on every axis of every module listed (Escape)"}, "STOP ALL"),
        el("span", {class: "hint"}, "Every module served on this link, and those the module scan (Overview) found; positions in microsteps, velocities in the module's units.")),
      el("div", {id: "bus-modules", class: "bus-modules"}));
  },
  show() { refresh(); B.timer = setInterval(refresh, 400); },
  hide() { clearInterval(B.timer); B.timer = null; },
});
})();
