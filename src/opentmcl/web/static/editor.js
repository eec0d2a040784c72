// The "program" view: the TMCL program editor with breakpoints and stepping (moved from app.js as-is).
"use strict";
(() => {
const {api, el, log} = window.OpenTMCL;
const $ = id => document.getElementById(id);
const D = {breakpoints: new Set(), errorLines: new Set(), currentLine: null, downloaded: false};

const MARKUP = `
    <h2>TMCL program</h2>
    <div class="toolbar">
      <button id="btn-assemble">Assemble</button>
      <button id="btn-download">Download</button>
      <button id="btn-run">Run</button>
      <button id="btn-stop">Stop</button>
      <button id="btn-step">Step</button>
      <button id="btn-reset">Reset</button>
      <span id="prog-message"></span>
    </div>
    <div class="columns">
      <div id="editor-wrap">
        <div id="editor-gutter"></div>
        <div id="editor-area">
          <div id="editor-backdrop"></div>
          <textarea id="editor" spellcheck="false" wrap="off"></textarea>
        </div>
      </div>
      <div id="prog-state">
        <table>
          <tr><th>State</th><td id="prog-mode">-</td></tr>
          <tr><th>PC</th><td id="prog-pc">-</td></tr>
          <tr><th>Line</th><td id="prog-line">-</td></tr>
          <tr><th>A</th><td id="prog-a">-</td></tr>
          <tr><th>X</th><td id="prog-x">-</td></tr>
          <tr><th>Flags</th><td id="prog-flags">-</td></tr>
        </table>
        <h3>User variables</h3>
        <table id="prog-vars"></table>
        <p class="hint">Click a line number to set a breakpoint. Run with breakpoints single-steps to the next one.</p>
      </div>
    </div>
    <div id="asm-errors"></div>`;

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

async function loadProgram() {
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
}

OpenTMCL.registerView("program", {
  mount(root, ctx) {
    root.innerHTML = MARKUP;
    setupEditor();
    ctx.onState(st => showProgramState(st.program));
    loadProgram();
  },
});
})();
