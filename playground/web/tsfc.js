// The tsfc module's loader and calling convention (docs/playground.md).
// tsfc_playground.wasm is a wasm32-wasip1 module exporting plain functions:
// strings cross as UTF-8 bytes in its memory (tsfc_alloc gives a buffer to
// fill; each call takes its buffers and leaves a JSON answer at
// tsfc_result_ptr / tsfc_result_len). The few WASI calls the Rust standard
// library makes are answered here: the clock, randomness, stderr (panic
// messages, passed to `log`); no files, no environment, no network.
"use strict";

const WASI_EBADF = 8;
const WASI_ENOSYS = 52;

/** Instantiates the compiled `module`; `log(fd, line)` gets stdout/stderr lines. */
async function tsfcInstantiate(module, log) {
  let memory = null;
  const view = () => new DataView(memory.buffer);
  const pending = { 1: "", 2: "" };
  const decoder = new TextDecoder();
  const zeroSizes = (count, size) => {
    view().setUint32(count, 0, true);
    view().setUint32(size, 0, true);
    return 0;
  };
  const wasi = {
    fd_write(fd, iovs, n, written) {
      if (fd !== 1 && fd !== 2) return WASI_EBADF;
      const dv = view();
      let total = 0;
      for (let i = 0; i < n; i++) {
        const ptr = dv.getUint32(iovs + 8 * i, true);
        const len = dv.getUint32(iovs + 8 * i + 4, true);
        pending[fd] += decoder.decode(new Uint8Array(memory.buffer, ptr, len));
        total += len;
      }
      let k;
      while ((k = pending[fd].indexOf("\n")) >= 0) {
        log(fd, pending[fd].slice(0, k));
        pending[fd] = pending[fd].slice(k + 1);
      }
      dv.setUint32(written, total, true);
      return 0;
    },
    clock_time_get(_id, _precision, out) {
      view().setBigUint64(out, BigInt(Math.round(performance.now() * 1e6)), true);
      return 0;
    },
    clock_res_get(_id, out) {
      view().setBigUint64(out, 1000n, true);
      return 0;
    },
    random_get(buf, len) {
      const bytes = new Uint8Array(memory.buffer, buf, len);
      for (let i = 0; i < len; i += 65536) {
        crypto.getRandomValues(bytes.subarray(i, Math.min(len, i + 65536)));
      }
      return 0;
    },
    environ_sizes_get: zeroSizes,
    args_sizes_get: zeroSizes,
    environ_get: () => 0,
    args_get: () => 0,
    fd_prestat_get: () => WASI_EBADF,
    sched_yield: () => 0,
    proc_exit(code) {
      throw new Error(`tsfc exited with code ${code}`);
    },
  };
  const imports = {};
  for (const imp of WebAssembly.Module.imports(module)) {
    imports[imp.module] = imports[imp.module] || {};
    if (imp.kind !== "function") continue;
    const own = imp.module === "wasi_snapshot_preview1" ? wasi[imp.name] : undefined;
    imports[imp.module][imp.name] = own || (() => WASI_ENOSYS);
  }
  const instance = await WebAssembly.instantiate(module, imports);
  const ex = instance.exports;
  memory = ex.memory;
  if (ex._initialize) ex._initialize();
  const encoder = new TextEncoder();
  const pass = (s) => {
    const bytes = encoder.encode(s);
    const ptr = ex.tsfc_alloc(bytes.length) >>> 0;
    new Uint8Array(memory.buffer, ptr, bytes.length).set(bytes);
    return [ptr, bytes.length];
  };
  const answer = (len) => {
    const ptr = ex.tsfc_result_ptr() >>> 0;
    return JSON.parse(decoder.decode(new Uint8Array(memory.buffer, ptr, len >>> 0)));
  };
  return {
    about: () => answer(ex.tsfc_about()),
    // The plots' font (DejaVu Sans) as a copy of its bytes.
    font: () => {
      const len = ex.tsfc_font() >>> 0;
      return new Uint8Array(memory.buffer, ex.tsfc_result_ptr() >>> 0, len).slice().buffer;
    },
    check: (name, text) => answer(ex.tsfc_check(...pass(name), ...pass(text))),
    certify: (name, text) => answer(ex.tsfc_certify(...pass(name), ...pass(text))),
    simulate: (name, text, horizon) =>
      answer(ex.tsfc_simulate(...pass(name), ...pass(text), horizon)),
  };
}

if (typeof module !== "undefined") module.exports = { tsfcInstantiate };
