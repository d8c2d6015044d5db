// The playground page: editor with highlighting and as-you-type diagnostics,
// Certify and Simulate (in workers: one checks while the other solves), the
// summary, certificate table, plots and generated files. No network request
// leaves the page's own folder. docs/playground.md.
"use strict";

const $ = (id) => document.getElementById(id);
const source = $("source");
const CHECK_DELAY_MS = 250;

/** A worker with request/answer promises; `restart` replaces it (Stop). */
function tsfcWorker() {
  let worker = null;
  let next = 0;
  const waiting = new Map();
  const start = () => {
    worker = new Worker("worker.js");
    worker.onmessage = (e) => {
      if (e.data.log !== undefined) {
        (e.data.fd === 2 ? console.error : console.log)(`tsfc: ${e.data.log}`);
        return;
      }
      const w = waiting.get(e.data.id);
      waiting.delete(e.data.id);
      if (w) (e.data.ok ? w.resolve(e.data) : w.reject(new Error(e.data.error)));
    };
    worker.onerror = (e) => console.error(`worker: ${e.message}`);
  };
  start();
  return {
    call(msg) {
      const id = ++next;
      return new Promise((resolve, reject) => {
        waiting.set(id, { resolve, reject });
        worker.postMessage({ id, ...msg });
      });
    },
    restart() {
      worker.terminate();
      for (const w of waiting.values()) w.reject(new Error("stopped"));
      waiting.clear();
      start();
    },
  };
}

const checker = tsfcWorker();
const solver = tsfcWorker();
let about = null;
let diagnostics = [];
let files = [];
let specName = "playground.tsf";

function status(text, error) {
  $("status").textContent = text;
  $("status").className = error ? "error" : "";
}

const escapeHtml = (s) =>
  s.replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" })[c]);

const KEYWORDS = new Set(("tsf controller const fn state input disturbance output signal premise rules rule " +
  "objective relaxation lyapunov trigger emit precision simulate dynamics monte_carlo sweep columns modes mode adaptive plant").split(" "));
const WORDS = new Set(("saturate bound energy range sigma is and about at for in with step scale offset " +
  "converged by estimate robust rate bounds init layer region").split(" "));
const TOKEN = /(\/\/[^\n]*|\/\*[\s\S]*?(?:\*\/|$))|([A-Za-z_][A-Za-z0-9_]*)(?=(\s*\()?)|((?:[0-9]+(?:\.[0-9]+)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?)/g;

/** The spec as highlighted HTML, diagnostics' spans underlined (UTF-16 offsets). */
function highlight(text, marks) {
  const html = (s) => escapeHtml(s).replace(TOKEN, (m, com, word, call, num) => {
    if (com) return `<span class="com">${m}</span>`;
    if (num) return `<span class="num">${m}</span>`;
    if (KEYWORDS.has(word)) return `<span class="kw">${m}</span>`;
    if (WORDS.has(word)) return `<span class="op2">${m}</span>`;
    if (call !== undefined) return `<span class="fn">${m}</span>`;
    return m;
  });
  const cuts = [];
  for (const d of marks) {
    let [a, b] = [d.from, Math.max(d.to, d.from + 1)];
    if (cuts.some((c) => a < c.b && c.a < b)) continue;
    cuts.push({ a, b, cls: d.severity === "error" ? "err" : "warn", msg: d.message });
  }
  cuts.sort((x, y) => x.a - y.a);
  let out = "";
  let at = 0;
  for (const c of cuts) {
    if (c.a < at || c.a > text.length) continue;
    const b = Math.min(c.b, text.length);
    out += html(text.slice(at, c.a));
    const inner = text.slice(c.a, b);
    out += `<span class="${c.cls}" title="${escapeHtml(c.msg)}">${inner === "\n" || inner === "" ? " " : html(inner)}</span>`;
    at = b;
  }
  return out + html(text.slice(at)) + "\n";
}

/** UTF-16 offset of a 1-based line and character column. */
function offsetOf(text, line, column) {
  let i = 0;
  for (let l = 1; l < line; l++) {
    const k = text.indexOf("\n", i);
    if (k < 0) return text.length;
    i = k + 1;
  }
  let chars = 1;
  while (chars < column && i < text.length && text[i] !== "\n") {
    i += text.codePointAt(i) > 0xffff ? 2 : 1;
    chars++;
  }
  return i;
}

function render() {
  const text = source.value;
  const marks = diagnostics.map((d) => ({
    from: offsetOf(text, d.line, d.column),
    to: offsetOf(text, d.end_line, d.end_column),
    severity: d.severity,
    message: d.message,
  }));
  $("highlight").innerHTML = highlight(text, marks);
  $("highlight").scrollTop = source.scrollTop;
  $("highlight").scrollLeft = source.scrollLeft;
}

function showDiagnostics(list, error) {
  diagnostics = list;
  const ul = $("diagnostics");
  ul.textContent = "";
  if (error) {
    const li = document.createElement("li");
    li.className = "error";
    li.textContent = error;
    ul.append(li);
  }
  for (const d of list) {
    const li = document.createElement("li");
    li.className = d.severity;
    li.dataset.line = d.line;
    li.textContent = `line ${d.line}, column ${d.column}: ${d.severity}: ${d.message}` +
      (d.label ? ` (${d.label})` : "") + (d.help ? ` — help: ${d.help}` : "");
    ul.append(li);
  }
  render();
}

let checkTimer = null;
let checkSeq = 0;
async function check() {
  const seq = ++checkSeq;
  try {
    const r = (await checker.call({ op: "check", name: specName, text: source.value })).result;
    if (seq !== checkSeq) return;
    showDiagnostics(r.diagnostics || [], r.error);
    if (r.error) status(r.error, true);
    else status(r.ok ? `ok: ${r.summary || "no errors"}` : `${r.diagnostics.filter((d) => d.severity === "error").length} error(s)`, !r.ok);
  } catch (e) {
    if (seq === checkSeq) status(`check failed: ${e.message}`, true);
  }
}
source.addEventListener("input", () => {
  render();
  clearTimeout(checkTimer);
  checkTimer = setTimeout(check, CHECK_DELAY_MS);
});
source.addEventListener("scroll", render);

function busy(on, what) {
  $("certify").disabled = on;
  $("simulate").disabled = on;
  $("stop").disabled = !on;
  if (on) status(`${what}… (running in a worker; Stop cancels)`);
}

function certificateTable(report) {
  const table = $("certificate");
  const thead = table.querySelector("thead");
  const tbody = table.querySelector("tbody");
  thead.textContent = "";
  tbody.textContent = "";
  const c = report && report.certificate;
  table.classList.toggle("hidden", !c);
  if (!c) return;
  thead.innerHTML = "<tr><th>condition</th><th>size</th><th>strict</th><th>margin</th><th>error bound</th><th>ok</th></tr>";
  for (const l of c.lmis) {
    const tr = document.createElement("tr");
    for (const [v, cls] of [[l.name], [l.size, "num"], [l.strict ? "yes" : "no"],
      [l.margin.toExponential(4), "num"], [l.error_bound.toExponential(2), "num"], [l.ok ? "✓" : "✗"]]) {
      const td = document.createElement("td");
      td.textContent = v;
      if (cls) td.className = cls;
      tr.append(td);
    }
    tbody.append(tr);
  }
}

function showFiles(list) {
  files = list;
  const sel = $("files");
  sel.textContent = "";
  for (const f of list) sel.append(new Option(f.name, f.name));
  $("code").classList.toggle("hidden", list.length === 0);
  showFile();
}
function showFile() {
  const f = files.find((x) => x.name === $("files").value);
  $("file").textContent = f ? f.text : "";
}
$("files").addEventListener("change", showFile);
$("copy").addEventListener("click", async () => {
  try {
    await navigator.clipboard.writeText($("file").textContent);
    status(`copied ${$("files").value}`);
  } catch (e) {
    status(`copy refused by the browser: ${e.message}`, true);
  }
});
$("download").addEventListener("click", () => {
  const f = files.find((x) => x.name === $("files").value);
  if (!f) return;
  const a = document.createElement("a");
  a.href = URL.createObjectURL(new Blob([f.text], { type: "text/plain" }));
  a.download = f.name;
  a.click();
  setTimeout(() => URL.revokeObjectURL(a.href), 1000);
});

async function certify() {
  busy(true, "certifying");
  $("summary").textContent = "";
  $("plots").textContent = "";
  try {
    const { result: r, ms } = await solver.call({ op: "certify", name: specName, text: source.value });
    window.lastCertify = { result: r, ms };
    if (r.status === "error") {
      $("summary").textContent = (r.rendered || "") + r.error;
      certificateTable(null);
      showFiles([]);
      status(r.error, true);
    } else {
      $("summary").textContent = r.summary;
      certificateTable(JSON.parse(r.report));
      showFiles(r.files);
      status(`${r.status} in ${(ms / 1000).toFixed(2)} s`, r.status !== "certified");
    }
  } catch (e) {
    status(`certify: ${e.message}`, true);
  } finally {
    busy(false);
  }
}

async function simulate() {
  busy(true, "simulating");
  $("plots").textContent = "";
  const h = parseFloat($("horizon").value);
  try {
    const { result: r, ms } = await solver.call({ op: "simulate", name: specName, text: source.value, horizon: Number.isFinite(h) ? h : 0 });
    window.lastSimulate = { result: r, ms };
    if (r.error) {
      status(r.error, true);
      return;
    }
    const m = r.metrics;
    for (const p of r.plots) {
      // Inline (not an <img>), so the text uses the page's registered DejaVu
      // Sans (style.css), the font tsfc ships, not a system font.
      const svg = new DOMParser().parseFromString(p.svg, "image/svg+xml").documentElement;
      if (svg.nodeName !== "svg") continue;
      svg.setAttribute("role", "img");
      svg.setAttribute("aria-label", p.name);
      $("plots").append(document.importNode(svg, true));
    }
    const notes = [...r.warnings, ...r.failures].join("; ");
    status(`simulated in ${(ms / 1000).toFixed(2)} s: ${m.samples} samples, final ||x|| = ${m.final_state_norm.toExponential(3)}` +
      `${m.converged ? ", converged" : ", not converged"}${notes ? "; " + notes : ""}`, r.failures.length > 0);
  } catch (e) {
    status(`simulate: ${e.message}`, true);
  } finally {
    busy(false);
  }
}

$("certify").addEventListener("click", certify);
$("simulate").addEventListener("click", simulate);
$("stop").addEventListener("click", () => {
  solver.restart();
  busy(false);
  status("stopped", true);
});

function openExample(name) {
  const ex = about.examples.find((e) => e.name === name);
  if (!ex) return;
  specName = ex.name;
  $("examples").value = ex.name;
  source.value = ex.text;
  showFiles([]);
  certificateTable(null);
  $("summary").textContent = "";
  $("plots").textContent = "";
  render();
  check();
}
$("examples").addEventListener("change", (e) => {
  if (e.target.value) openExample(e.target.value);
  else specName = "playground.tsf";
});

(async () => {
  try {
    about = (await checker.call({ op: "about" })).result;
  } catch (e) {
    status(`the compiler did not load: ${e.message}`, true);
    console.error(`tsfc playground: ${e.message}`);
    return;
  }
  try {
    // The plots' font, from the module (the bytes the native plots embed).
    const face = new FontFace("tsfc-sans", (await checker.call({ op: "font" })).result);
    document.fonts.add(await face.load());
  } catch (e) {
    console.warn(`tsfc playground: the plots' font did not load: ${e.message}`);
  }
  for (const e of about.examples) $("examples").append(new Option(e.name, e.name));
  const l = about.limits;
  $("limits").textContent = `Limits of the page: specs up to ${l.spec_bytes >> 10} KiB, models up to n = ${l.states} states and ` +
    `${l.rules} rules, simulations up to ${l.sim_steps} steps (the command line takes more). Everything runs in this tab; nothing is sent anywhere.`;
  certificateTable(null);
  showFiles([]);
  const wanted = new URLSearchParams(location.search).get("example");
  openExample(wanted || "zhang2013_multiobjective.tsf");
  document.body.dataset.ready = "1";
})();
