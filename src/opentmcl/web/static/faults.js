// Faults on demand (docs/faults.md, docs/dashboard.md "Faults"): a panel of the overview, shown when
// the link has a fault plan; the button fires the chosen named fault (the server checks the name),
// and the list of what fired follows the plan while the panel is in view.
"use strict";
(() => {
const {api, el, log} = window.OpenTMCL;
const $ = id => document.getElementById(id);
const REFRESH_MS = 1000;
let shown = "";

function show(st) {
  const text = st.fired.join("\n");
  if (text === shown) return;
  shown = text;
  $("faults-fired").replaceChildren(...st.fired.slice().reverse().map(f => el("li", {}, f)));
}

async function trigger() {
  const name = $("fault-name").value;
  log(`> fault ${name}`, "req");
  try {
    show(await api("api/faults/trigger", {name}));
    log(`  ${name}: fired`, "ok");
  } catch (e) { log(`  ${e.message}`, "err"); }
}

async function refresh() {
  const panel = $("faults-panel");
  if (!panel || panel.offsetParent === null || document.hidden) return;
  try { show(await api("api/faults")); } catch (_) { /* the next look tells */ }
}

async function mount() {
  let st;
  try { st = await api("api/faults"); } catch (_) { return; }
  if (st.seed === null) return;   // no fault plan on this link
  const controls = st.names.length ? [
    el("select", {id: "fault-name", title: "the named faults of the served fault plan"},
       ...st.names.map(n => el("option", {value: n}, n))),
    el("button", {id: "btn-fault", onclick: trigger}, "Trigger")] : [];
  $("view-overview").append(el("div", {id: "faults-panel"},
    el("h2", {}, "Faults"),
    el("div", {class: "toolbar"}, ...controls, el("span", {class: "hint"}, `seed ${st.seed}`)),
    el("ul", {id: "faults-fired", class: "hint"})));
  show(st);
  setInterval(refresh, REFRESH_MS);
}

mount();
})();
