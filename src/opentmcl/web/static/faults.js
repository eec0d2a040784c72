// Faults on demand (docs/faults.md, docs/dashboard.md "Faults"): a panel of the overview, shown when
// the served plan names faults; the button fires the chosen one (the server checks the name).
"use strict";
(() => {
const {api, el, log} = window.OpenTMCL;
const $ = id => document.getElementById(id);

function show(st) {
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

async function mount() {
  let st;
  try { st = await api("api/faults"); } catch (_) { return; }
  if (!st.names.length) return;
  $("view-overview").append(el("div", {id: "faults-panel"},
    el("h2", {}, "Faults"),
    el("div", {class: "toolbar"},
      el("select", {id: "fault-name", title: "the named faults of the served fault plan"},
         ...st.names.map(n => el("option", {value: n}, n))),
      el("button", {id: "btn-fault", onclick: trigger}, "Trigger"),
      el("span", {class: "hint"}, `seed ${st.seed}`)),
    el("ul", {id: "faults-fired", class: "hint"})));
  show(st);
}

mount();
})();
