// The "program" view: a CodeMirror 5 editor (static/vendor/codemirror) for TMCL-IDE source with
// highlighting, every assembler error and warning marked at once, breakpoints and stepping
// (docs/dashboard-program.md).
"use strict";
(() => {
const {api, el, log} = window.OpenTMCL;
const $ = id => document.getElementById(id);
const D = {cm: null, stateSeq: 0, breakpoints: new Set(), currentLine: null, downloaded: false, marks: [], lineCount: 0,
           diagnostics: []};

// ------------------------------------------------------------------ the TMCL mode
// Words as the manuals print them (TMCM-6212 3.4.1, 3.6; PD86-1180 4.6; PD28-1021 3.5); a browser
// test compares them with the assembler's tables (protocol/opcodes.py).
const WORDS = {
  mnemonics: ("ROR ROL MST MVP SAP GAP STAP RSAP SGP GGP STGP RSGP RFS SIO GIO CALC COMP JC JA CSUB RSUB " +
              "EI DI WAIT STOP SCO GCO CCO CALCX AAP AGP CLE VECT RETI ACO CALCVV CALCVA CALCAV CALCVX " +
              "CALCXV CALCV MVPA RST DJNZ ROLA RORA SIV GIV AIV CALL UF0 UF1 UF2 UF3 UF4 UF5 UF6 UF7 RAW").split(" "),
  // type operands: MVP, RFS, CALC/CALCX, WAIT, CLE
  types: ("ABS REL COORD START STOP STATUS ADD SUB MUL DIV MOD AND OR XOR NOT LOAD SWAP " +
          "TICKS POS REFSW LIMSW RFS ALL ETO EAL EDV EPO ESD").split(" "),
  // JC / CALL conditions
  conditions: "ZE NZ EQ NE GT GE LT LE ETO EAL EDV EPO ESD".split(" "),
};
const MNEMONIC = new Set(WORDS.mnemonics), CONDITION = new Set(WORDS.conditions), TYPE = new Set(WORDS.types);
const CONDITIONAL = new Set(["JC", "CALL"]);
const NUMBER = /^(?:0[xX][0-9A-Fa-f]+|\$[0-9A-Fa-f]+|0[bB][01]+|[0-9]+)/;
const NAME = /^[A-Za-z_][A-Za-z0-9_]*/;

function tmclMode() {
  return {
    startState: () => ({where: "start", mnemonic: null}),
    token(stream, state) {
      if (stream.sol()) { state.where = "start"; state.mnemonic = null; }
      if (stream.eatSpace()) return null;
      if (stream.match("//")) { stream.skipToEnd(); return "comment"; }
      if (state.where === "start" && stream.match(/^#\s*[A-Za-z_]+/)) { state.where = "directive"; return "meta"; }
      if (state.where === "directive") { stream.match(/^(?:[^/]|\/(?!\/))+/); return "string"; }
      if (stream.match(NUMBER)) return "number";
      const word = stream.match(NAME);
      if (word) return wordStyle(word[0], stream, state);
      return stream.next() === "," ? null : "operator";
    },
    lineComment: "//",
  };
}

function wordStyle(word, stream, state) {
  const upper = word.toUpperCase();
  if (state.where === "start") {
    if (stream.match(/^\s*:/, false)) return "def";                                 // Label:
    if (stream.match(/^\s*=/, false)) { state.where = "operands"; return "def"; }  // Name = ...
    state.where = "operands";
    state.mnemonic = upper;
    return MNEMONIC.has(upper) ? "keyword" : "variable";
  }
  if (CONDITIONAL.has(state.mnemonic) && CONDITION.has(upper)) return "builtin";
  if (TYPE.has(upper)) return "atom";
  return "variable";
}

// ------------------------------------------------------------------ markup
const MARKUP = `
    <h2>TMCL program</h2>
    <div class="toolbar">
      <button id="btn-assemble">Assemble</button>
      <button id="btn-download">Download</button>
      <button id="btn-run" title="run (129) from the current address; a download sets it to the first instruction">Run</button>
      <button id="btn-run-start" title="reset (131), then run: the program from its first instruction">Run from start</button>
      <button id="btn-stop">Stop</button>
      <button id="btn-step">Step</button>
      <button id="btn-reset">Reset</button>
      <span class="sep"></span>
      <button id="btn-readback" title="read the module's program memory (command 134), disassembled, and compare it with the editor">Read back</button>
      <label class="file-button" title="open a .tmc file from this computer into the editor">Open .tmc… <input type="file" id="prog-open" accept=".tmc,.TMC,text/plain"></label>
      <button id="btn-save" title="save the editor's text as a .tmc file on this computer">Save .tmc</button>
      <span id="prog-message"></span>
    </div>
    <div id="readback-panel" hidden></div>
    <div class="columns">
      <div id="program-editor"></div>
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
        <p class="hint">Click a line number to set a breakpoint. Run with breakpoints single-steps to the next one.
        Errors and warnings are marked in the left gutter and underlined; hover for the message.</p>
      </div>
    </div>
    <div id="asm-errors"></div>`;

// The starting program, with the values of the module's own manual example: internal units (0..2047)
// on the PD86-1180 (manual 3.2), pps on the others (TMCM-6212 manual 2.4). 51200 is out of range
// for a TMC429 module, whose SAP would refuse it with status 4 and leave the motor at rest.
function example(ov) {
  const pps = !ov || (ov.velocity_unit || "pps") === "pps";  // the unit of AP3 (web/service.py overview)
  const [speed, accel, target, manual] = pps ? [51200, 51200, 51200, "TMCM-6212 manual 2.4"]
                                             : [500, 50, 10000, `${ov.module} manual 3.2`];
  return `// Move motor 0 back and forth (${manual})
    SAP 4, 0, ${speed}        // maximum positioning speed
    SAP 5, 0, ${accel}        // maximum acceleration
    SGP 0, 2, 0            // user variable 0 counts the moves
Loop:
    MVP ABS, 0, ${target}
    WAIT POS, 0, 0
    MVP ABS, 0, 0
    WAIT POS, 0, 0
    GGP 0, 2
    CALC ADD, 1
    AGP 0, 2
    JA Loop
`;
}

const SOURCE_KEY = `opentmcl-source ${location.pathname}`;  // each module keeps its own program
const BP_GUTTER = "cm-breakpoints", DIAG_GUTTER = "cm-asm-diagnostics";

// ------------------------------------------------------------------ breakpoints
function renderBreakpoints() {
  const cm = D.cm;
  cm.operation(() => {
    cm.clearGutter(BP_GUTTER);
    for (let i = 1; i <= cm.lineCount(); i++) {
      const bp = D.breakpoints.has(i);
      cm.setGutterMarker(i - 1, BP_GUTTER, el("div", {id: `gutter-${i}`, class: bp ? "bp" : "",
        title: bp ? "breakpoint (click to clear)" : "click to set a breakpoint"}, bp ? "●" : ""));
    }
  });
  D.lineCount = cm.lineCount();
}

async function toggleBreakpoint(line) {
  if (D.breakpoints.has(line)) D.breakpoints.delete(line); else D.breakpoints.add(line);
  renderBreakpoints();
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

// ------------------------------------------------------------------ errors and warnings
function clearDiagnostics() {
  for (const m of D.marks) m.clear();
  D.marks = [];
  D.cm.clearGutter(DIAG_GUTTER);
}

function tokenRange(cm, line, column) {
  const text = cm.getLine(line) || "";
  const ch = Math.min(Math.max(column - 1, 0), text.length);
  const word = /^[A-Za-z0-9_$]+/.exec(text.slice(ch));
  const end = word ? ch + word[0].length : Math.min(ch + 1, text.length);
  return end > ch ? [ch, end] : [Math.max(0, text.length - 1), text.length];
}

function showDiagnostics(diags, more) {
  const cm = D.cm;
  D.diagnostics = diags;
  clearDiagnostics();
  const byLine = new Map();
  diags.forEach((d, i) => {
    if (d.file !== "<editor>" || d.line < 1 || d.line > cm.lineCount()) return;
    const [from, to] = tokenRange(cm, d.line - 1, d.column);
    D.marks.push(cm.markText({line: d.line - 1, ch: from}, {line: d.line - 1, ch: to},
      {className: `cm-asm-${d.severity}`, attributes: {title: d.message, "data-diagnostic": String(i)}}));
    if (!byLine.has(d.line)) byLine.set(d.line, []);
    byLine.get(d.line).push(d);
  });
  for (const [line, list] of byLine) {
    const severity = list.some(d => d.severity === "error") ? "error" : "warning";
    cm.setGutterMarker(line - 1, DIAG_GUTTER, el("div", {class: `asm-mark ${severity}`, id: `diag-${line}`,
      title: list.map(d => `${d.severity}: ${d.message}`).join("\n")}, severity === "error" ? "✖" : "▲"));
  }
  const items = diags.map(d => {
    const at = d.file === "<editor>" ? `line ${d.line}, column ${d.column}` : `${d.file}:${d.line}:${d.column}`;
    const row = el("div", {class: `asm-${d.severity}`}, `${at}: ${d.severity}: ${d.message}`);
    if (d.file === "<editor>") row.addEventListener("click", () => { cm.focus(); cm.setCursor(d.line - 1, d.column - 1); });
    return row;
  });
  if (more) items.push(el("div", {class: "asm-more"}, `... and ${more} more`));
  $("asm-errors").replaceChildren(...items);
}

function counts(r) {
  const e = r.errors.length, w = (r.warnings || []).length, more = r.more ? ` (+${r.more} more)` : "";
  return `${e} error${e === 1 ? "" : "s"}, ${w} warning${w === 1 ? "" : "s"}${more}`;
}

async function assembleOnly(download) {
  const source = D.cm.getValue();
  try {
    const r = await api(download ? "api/program/download" : "api/program/assemble", {source});
    showDiagnostics(r.diagnostics || r.errors || [], r.more || 0);
    if (!r.ok) { message(counts(r), true); return false; }
    const warned = (r.warnings || []).length ? ` (${counts(r)})` : "";
    if (download) {
      D.downloaded = true;
      await pushBreakpoints();
      message(`downloaded ${r.count} instructions${warned}; Run starts at the first one`);
    } else {
      message(`assembled: ${r.count} instructions${warned}`);
    }
    return true;
  } catch (e) { message(e.message, true); return false; }
}

async function programAction(name, label = name) {
  try {
    const st = await api(`api/program/${name}`, {});
    // A run to a breakpoint answers mid-run; the live state (WebSocket) brings where it stops,
    // and may already have: a late mid-run answer must not overwrite it.
    if (!st.stepping_to_breakpoint) showProgramState(st);
    message(label);
  } catch (e) { message(e.message, true); }
}

// ------------------------------------------------------------------ program state
function setCurrentLine(line) {
  const cm = D.cm;
  if (line === D.currentLine) return;
  if (D.currentLine && D.currentLine <= cm.lineCount()) cm.removeLineClass(D.currentLine - 1, "background", "current-line");
  D.currentLine = line;
  if (line && line <= cm.lineCount()) {
    cm.addLineClass(line - 1, "background", "current-line");
    cm.scrollIntoView({line: line - 1, ch: 0}, 40);
  }
}

function showProgramState(p) {
  if (!p || p.mode === null || p.mode === undefined) return;
  // a state read before the one shown (a live update that crossed a Step's answer) is stale
  if (p.seq !== undefined) { if (p.seq < D.stateSeq) return; D.stateSeq = p.seq; }
  $("prog-mode").textContent = p.mode_name + (p.waiting ? " (waiting)" : "") + (p.stepping_to_breakpoint ? " (to breakpoint)" : "");
  $("prog-pc").textContent = p.pc;
  $("prog-line").textContent = p.line ?? "-";
  $("prog-a").textContent = p.a;
  $("prog-x").textContent = p.x;
  $("prog-flags").textContent = p.flags;
  $("prog-vars").replaceChildren(...Object.entries(p.variables || {}).map(([n, v]) =>
    el("tr", {}, el("th", {}, `var ${n}`), el("td", {id: `prog-var-${n}`}, v ?? "-"))));
  setCurrentLine(D.downloaded ? p.line : null);
}

// ------------------------------------------------------------------ read-back, open and save
const MAX_FILE = 1 << 20;   // the dashboard's body limit (docs/dashboard.md "Threat model")

function panel(...kids) {
  const box = $("readback-panel");
  box.replaceChildren(...kids);
  box.hidden = kids.length === 0;
}

async function readBack() {
  message("reading the program memory (134)…");
  log("> 134, 0, 0, <address> for each program memory location until the empty ones", "req");
  try {
    const r = await api("api/program/readback", {source: D.cm.getValue()});
    D.readback = r;
    log(`  ${r.count} instructions read`, "ok");
    const summary = r.same ? `The module holds ${r.count} instructions, the same as the editor's program.`
      : !r.editor_ok ? `The module holds ${r.count} instructions; the editor's program does not assemble, so all of it is shown as different.`
      : `The module holds ${r.count} instructions; ${r.differences.length} address(es) differ from the editor's program.`;
    const rows = r.differences.slice(0, 50).map(d => el("tr", {}, el("td", {class: "num"}, d.address), el("td", {class: "num"}, d.line ?? "-"),
      el("td", {}, d.editor ?? "(none)"), el("td", {}, d.module ?? "(none)")));
    panel(el("div", {id: "readback-summary", class: r.same ? "ok" : ""}, summary),
      ...(rows.length ? [el("table", {class: "params", id: "readback-differences"},
        el("tr", {}, ...["address", "editor line", "editor", "module"].map(h => el("th", {}, h))), ...rows)] : []),
      ...(r.diff.length ? [el("pre", {id: "readback-diff", class: "diff"}, ...r.diff.map(line =>
        el("div", {class: line.startsWith("+") ? "add" : line.startsWith("-") ? "del" : ""}, line)))] : []),
      el("div", {class: "toolbar"},
        el("button", {id: "btn-readback-open", class: "primary", onclick: () => {
          D.cm.setValue(r.source); panel(); message(`read back: ${r.count} instructions in the editor`);
          log(`  the module's program (${r.count} instructions) is in the editor`, "ok");
        }}, "Open in editor"),
        el("button", {id: "btn-readback-close", onclick: () => panel()}, "Close")));
    message(`read back ${r.count} instructions`);
  } catch (e) { message(e.message, true); log(`  ${e.message}`, "err"); }
}

async function openFile(file) {
  if (!file) return;
  if (file.size > MAX_FILE) { message(`${file.name}: larger than ${MAX_FILE} bytes`, true); return; }
  const text = await file.text();
  D.cm.setValue(text);
  message(`opened ${file.name}`);
  log(`opened ${file.name} (${text.split("\n").length} lines) from this computer into the editor`, "ok");
}

function saveFile() {
  const name = `${(D.ov && D.ov.module) || "program"}.tmc`;
  const a = el("a", {href: URL.createObjectURL(new Blob([D.cm.getValue()], {type: "text/plain"})), download: name});
  document.body.append(a); a.click(); a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 10000);
  log(`saved the editor's program as ${name} (a download of this browser)`, "ok");
}

// ------------------------------------------------------------------ setup
function setupEditor(root, ov) {
  CodeMirror.defineMode("tmcl", tmclMode);
  const cm = CodeMirror($("program-editor"), {
    value: localStorage.getItem(SOURCE_KEY) || example(ov), mode: "tmcl", lineNumbers: true, indentUnit: 4,
    tabSize: 4, indentWithTabs: false, gutters: [DIAG_GUTTER, BP_GUTTER, "CodeMirror-linenumbers"],
    extraKeys: {Tab: c => c.replaceSelection("    ")}, viewportMargin: 200,
  });
  D.cm = cm;
  cm.on("change", () => {
    localStorage.setItem(SOURCE_KEY, cm.getValue());
    D.downloaded = false;
    setCurrentLine(null);
    if (cm.lineCount() !== D.lineCount) renderBreakpoints();
  });
  cm.on("gutterClick", (_cm, line, gutter) => { if (gutter !== DIAG_GUTTER) toggleBreakpoint(line + 1); });
  $("btn-assemble").addEventListener("click", () => assembleOnly(false));
  $("btn-download").addEventListener("click", () => assembleOnly(true));
  $("btn-run").addEventListener("click", () => programAction("run"));
  $("btn-run-start").addEventListener("click", () => programAction("run_from_start", "run from start"));
  $("btn-stop").addEventListener("click", () => programAction("stop"));
  $("btn-step").addEventListener("click", () => programAction("step"));
  $("btn-reset").addEventListener("click", () => programAction("reset"));
  $("btn-readback").addEventListener("click", () => readBack());
  $("btn-save").addEventListener("click", () => saveFile());
  $("prog-open").addEventListener("change", ev => { openFile(ev.target.files[0]); ev.target.value = ""; });
  renderBreakpoints();
}

async function loadProgram() {
  try {  // the program the dashboard downloaded before (e.g. from another tab) is what runs
    const prog = await api("api/program");
    if (prog.source) {
      D.cm.setValue(prog.source);
      D.downloaded = true;
      D.breakpoints = new Set((prog.state.breakpoints || []).map(a => prog.lines[a]).filter(l => l));
      renderBreakpoints();
      showProgramState(prog.state);
    }
  } catch (e) { log(e.message, "err"); }
}

// For the browser tests and the curious: the editor, its words and its marks.
window.OpenTMCL.programEditor = {
  words: WORDS,
  get cm() { return D.cm; },
  setSource(text) { D.cm.setValue(text); },
  currentLine: () => D.currentLine,
  diagnostics: () => D.diagnostics,
};

OpenTMCL.registerView("program", {
  mount(root, ctx) {
    root.innerHTML = MARKUP;
    D.ov = ctx.overview;
    setupEditor(root, ctx.overview);
    ctx.onState(st => showProgramState(st.program));
    loadProgram();
  },
  show() { if (D.cm) D.cm.refresh(); },
});
})();
