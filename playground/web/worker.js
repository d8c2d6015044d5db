// The page's worker: runs tsfc (tsfc.js, tsfc_playground.wasm) off the page's
// thread, so a solve never freezes the editor. Messages in:
// {id, op: "about" | "font" | "check" | "certify" | "simulate", name, text, horizon};
// out: {id, ok: true, result, ms} or {id, ok: false, error}. A trap (a panic)
// loses the instance; the next message makes a fresh one.
"use strict";
importScripts("tsfc.js");

let compiled = null;
let tsfc = null;

async function ready() {
  if (!compiled) {
    const bytes = await (await fetch("tsfc_playground.wasm")).arrayBuffer();
    compiled = await WebAssembly.compile(bytes);
  }
  if (!tsfc) {
    // The module's stderr (a panic's message) goes to the page's console.
    tsfc = await tsfcInstantiate(compiled, (fd, line) => self.postMessage({ log: line, fd }));
  }
  return tsfc;
}

self.onmessage = async (e) => {
  const { id, op, name, text, horizon } = e.data;
  try {
    const t = await ready();
    const t0 = performance.now();
    let result;
    if (op === "about") result = t.about();
    else if (op === "font") result = t.font();
    else if (op === "check") result = t.check(name, text);
    else if (op === "certify") result = t.certify(name, text);
    else if (op === "simulate") result = t.simulate(name, text, horizon);
    else throw new Error(`unknown operation ${op}`);
    self.postMessage({ id, ok: true, result, ms: performance.now() - t0 });
  } catch (err) {
    tsfc = null;
    self.postMessage({ id, ok: false, error: String(err && err.message ? err.message : err) });
  }
};
