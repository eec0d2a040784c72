// The "parameters" view: axis and global parameter tables (moved from app.js as-is).
"use strict";
(() => {
const {api, el, log} = window.OpenTMCL;
const $ = id => document.getElementById(id);
const P = {axisParams: null, globalParams: null};

const MARKUP = `
    <h2>Parameters</h2>
    <div class="toolbar">
      <label>Axis <select id="param-axis"></select></label>
      <button id="btn-params-reload">Reload</button>
      <label><input type="checkbox" id="param-filter-writable"> writable only</label>
      <input id="param-filter" placeholder="filter by name">
    </div>
    <h3>Axis parameters</h3>
    <table id="param-axis-table" class="params"></table>
    <h3>Global parameters</h3>
    <table id="param-global-table" class="params"></table>`;

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
    P.axisParams = a.params; P.globalParams = g.params;
    renderParams();
  } catch (e) { log(e.message, "err"); }
}

function renderParams() {
  if (!P.axisParams) return;
  paramRows($("param-axis-table"), P.axisParams, "axis", Number($("param-axis").value || 0));
  paramRows($("param-global-table"), P.globalParams, "global", 0);
}

OpenTMCL.registerView("parameters", {
  mount(root, ctx) {
    root.innerHTML = MARKUP;
    const sel = $("param-axis");
    for (let i = 0; i < (ctx.overview ? ctx.overview.axes : 0); i++) sel.append(el("option", {value: i}, `${i}`));
    sel.addEventListener("change", loadParams);
    $("btn-params-reload").addEventListener("click", loadParams);
    $("param-filter").addEventListener("input", renderParams);
    $("param-filter-writable").addEventListener("change", renderParams);
    loadParams();
  },
});
})();
