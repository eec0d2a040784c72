// The module scan, a panel of the overview (docs/dashboard.md "Module scan"): which addresses of
// the link answer command 136 (firmware version); a module found opens in its own page.
"use strict";
(() => {
const {api, el, log} = window.OpenTMCL;
const $ = id => document.getElementById(id);
const S = {timer: null, link: null};
const BAUDS = [9600, 14400, 19200, 28800, 38400, 57600, 115200];  // GP65's rates a PC supports

const LINK_TEXT = {
  serial: "Serial link: the scan can also try the baud rates below (the link returns to its own afterwards).",
  fixed: "This link (TCP, the server's bus or an in-process module) has no baud rate: the scan tries addresses only.",
  can: "CAN: a connection reaches only the module of its CAN ID, so the scan asks that one address.",
};

function panel() {
  const num = (id, value, min, max, step) => el("input", {type: "number", id, value, min, max, step, class: "small"});
  return el("div", {id: "scan-panel"},
    el("h2", {}, "Modules on the link"),
    el("div", {class: "toolbar"},
      el("label", {}, "addresses ", num("scan-first", 1, 1, 255, 1), " … ", num("scan-last", 16, 1, 255, 1)),
      el("label", {}, "time-out per address ", num("scan-timeout", 0.1, 0.01, 0.5, 0.01), " s"),
      el("span", {id: "scan-bauds"}),
      el("button", {id: "btn-scan", onclick: start}, "Scan"),
      el("button", {id: "btn-scan-cancel", onclick: cancel, disabled: ""}, "Cancel"),
      el("span", {id: "scan-progress", class: "hint"})),
    el("p", {id: "scan-link", class: "hint"}),
    el("table", {id: "scan-results", class: "params"}));
}

function showLink(link) {
  if (S.link === link) return;
  S.link = link;
  $("scan-link").textContent = LINK_TEXT[link] || "";
  $("scan-bauds").replaceChildren(...(link === "serial" ? BAUDS.map(b =>
    el("label", {class: "baud"}, el("input", {type: "checkbox", value: b, id: `scan-baud-${b}`}), ` ${b}`)) : []));
}

function show(st) {
  showLink(st.link);
  $("btn-scan").disabled = st.running;
  $("btn-scan-cancel").disabled = !st.running;
  $("scan-progress").textContent = st.running ? `scanning… ${st.done}/${st.total}` :
    st.total ? `${st.cancelled ? "cancelled" : "done"}: ${st.found.length} found (${st.done}/${st.total} asked)` : "";
  if (st.error) $("scan-progress").textContent += ` — ${st.error}`;
  if (st.any_address) $("scan-progress").textContent += " — a module here answers every address (USB): listed at its own address only";
  const rows = [el("tr", {}, ...["address", "module", "firmware", "baud", ""].map(h => el("th", {}, h)))];
  for (const f of st.found) {
    const here = location.pathname.endsWith(`/m/${f.address}/`);
    const action = here ? el("span", {class: "hint"}, "this page") :
      el("button", {id: `scan-open-${f.address}`, onclick: () => open(f)}, "open");
    rows.push(el("tr", {id: `scan-found-${f.address}`}, el("td", {class: "num"}, f.address),
      el("td", {}, f.module || "(no profile)"), el("td", {}, f.version), el("td", {}, f.baud ?? "-"), el("td", {}, action)));
  }
  $("scan-results").replaceChildren(...rows);
  if (!st.running && S.timer) {
    clearInterval(S.timer); S.timer = null;
    log(`  ${st.cancelled ? "cancelled, " : ""}found ${st.found.length}: ` +
        (st.found.map(f => `${f.address} ${f.version}`).join(", ") || "none"), st.error ? "err" : "ok");
  }
}

async function poll() {
  try { show(await api("../../api/scan")); } catch (e) { log(e.message, "err"); }
}

async function start() {
  const bauds = [...document.querySelectorAll("#scan-bauds input:checked")].map(c => Number(c.value));
  const body = {first: Number($("scan-first").value), last: Number($("scan-last").value),
                timeout: Number($("scan-timeout").value), bauds};
  log(`> scan addresses ${body.first}…${body.last} with command 136 (firmware version)` +
      (bauds.length ? ` at ${bauds.join(", ")} baud` : ""), "req");
  try {
    show(await api("../../api/scan", body));
    if (!S.timer) S.timer = setInterval(poll, 300);
  } catch (e) { log(`  ${e.message}`, "err"); }
}

async function cancel() {
  try { show(await api("../../api/scan/cancel", {})); } catch (e) { log(e.message, "err"); }
}

async function open(f) {
  try {
    const r = await api("../../api/scan/open", {address: f.address});
    location.assign(r.url);
  } catch (e) { log(e.message, "err"); }
}

OpenTMCL.registerView("overview", {
  mount(root) { root.append(panel()); poll(); },
});
})();
