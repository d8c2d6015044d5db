#!/usr/bin/env python3
"""tsfc vs CVXPY + Clarabel on the same LMI problem (default: the Zhang spec).

The CVXPY problem is the one tsfc solves for the spec, LMI for LMI:

  variables  X = X' (n x n), M_j (m x n) for every rule j, g = gamma^2
  X >= eps I                                                  "X > 0"
  He(A_i X + B_i M_i) + 2 a X <= -eps I          for every i   decay Q_ii
  [He(A_i X + B_i M_i), D_i, (C X + E M_i)'; *, -g I, G'; *, *, -I] <= -eps I
                                                 for every i   hinf Q_ii
  g >= 0
  [1, x0'; x0, X] >= eps I                                    input norm: x0 in E(P,1)
  [X, M_j'; M_j, mu^2 I] >= eps I                for every j   input norm [j]
  minimize g

with tsfc's reduction for tanaka(s) when every rule shares B (as in the Zhang
spec): the pair LMIs equal sums of vertex LMIs and the slack Y = 0 is optimal,
so only the vertex LMIs Q_ii are solved (synth/relaxations/tanaka.rs). The margin eps
is tsfc's (1e-7). The model data (A_i, B_i, D_i, C, E, G, x0, mu, a, eps) are
read from `bench-compile --dump-model SPEC`, so both sides use the same numbers.

Timings (medians over --repeat fresh runs, seconds; the two sides' runs
alternate, tsfc first):
  CVXPY: construct (building the cvxpy expressions), compile (cvxpy's
  canonicalization, `problem.compilation_time`), solve (Clarabel's own
  `solver_stats.solve_time`), total = wall time of construct + `solve()` call.
  tsfc: the library pipeline from bench-compile (parse .. certify), whose total
  also includes parsing the spec, the model stage and the certificate.

End to end as a user runs them (fresh processes, --process N, default
--repeat): `python3 compare_cvxpy.py --solve-only MODEL.json` (interpreter
start, `import cvxpy`, reading the model, building and solving: the script a
user of CVXPY runs to get gamma) against `tsfc compile SPEC --out TMP` (parse ..
certify, plus generating and writing the Rust/C code and the report), wall
clock of each process, interleaved, medians. The in-process table above
isolates the solver; this one is what a user waits for.

Usage: python3 bench/compare_cvxpy.py [--spec SPEC] [--repeat N] [--json PATH] [--bench-bin BIN]
(needs `pip install cvxpy clarabel`; runs `cargo run --release -p tsfc --bin
bench-compile`, honouring CARGO_TARGET_DIR).
"""
import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time

import cvxpy as cp
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


BENCH_BIN = None  # a built bench-compile binary, else `cargo run`


def bench_compile(*args):
    """Runs bench-compile with `args` and returns its stdout."""
    if BENCH_BIN:
        cmd = [BENCH_BIN, *args]
    else:
        cmd = ["cargo", "run", "--quiet", "--release", "-p", "tsfc", "--bin", "bench-compile", "--", *args]
    out = subprocess.run(cmd, cwd=ROOT, check=True, capture_output=True, text=True)
    return out.stdout


def He(M):
    return M + M.T


def sym(E):
    """E is symmetric by construction; cvxpy wants it visibly symmetric
    (tsfc's lowering averages the two triangles the same way)."""
    return 0.5 * (E + E.T)


def build(d):
    """The cvxpy problem tsfc solves for the dumped model `d`; returns (problem, g)."""
    n, m = d["n"], d["m"]
    eps = d["eps"]
    rules = d["rules"]
    A = [np.array(r["a"]) for r in rules]
    B = [np.array(r["b"]) for r in rules]
    D = [np.array(r["d"]) for r in rules]
    if not all(np.array_equal(B[0], b) for b in B):
        sys.exit("this comparison implements the common-B reduction only (all B_i equal)")
    if d["tanaka_s"] is None:
        sys.exit("this comparison implements the tanaka(s) relaxation only")
    h = d["hinf"]
    C, E, G = np.array(h["c"]), np.array(h["e"]), np.array(h["g"])
    p, q = C.shape[0], D[0].shape[1]
    alpha = d["decay_rate"] or 0.0
    mu2 = d["input_norm"] ** 2
    x0 = np.array(d["x0"]).reshape(-1, 1)
    r = len(rules)

    X = cp.Variable((n, n), symmetric=True)
    M = [cp.Variable((m, n)) for _ in range(r)]
    g = cp.Variable()
    cons = [X >> eps * np.eye(n)]
    ups = [He(A[i] @ X + B[i] @ M[i]) for i in range(r)]
    cons += [sym(ups[i] + 2 * alpha * X) << -eps * np.eye(n) for i in range(r)]
    for i in range(r):
        out = C @ X + (E @ M[i] if np.any(E) else 0)
        Q = cp.bmat([
            [ups[i], D[i], out.T],
            [D[i].T, -g * np.eye(q), G.T],
            [out, G, -np.eye(p)],
        ])
        cons.append(sym(Q) << -eps * np.eye(n + q + p))
    cons.append(g >= 0)
    cons.append(sym(cp.bmat([[np.ones((1, 1)), x0.T], [x0, X]])) >> eps * np.eye(n + 1))
    for j in range(r):
        cons.append(sym(cp.bmat([[X, M[j].T], [M[j], mu2 * np.eye(m)]])) >> eps * np.eye(n + m))
    return cp.Problem(cp.Minimize(g), cons), g


def run_cvxpy(d):
    t0 = time.perf_counter()
    prob, g = build(d)
    t1 = time.perf_counter()
    prob.solve(solver=cp.CLARABEL)
    t2 = time.perf_counter()
    if prob.status != cp.OPTIMAL:
        sys.exit(f"CVXPY/Clarabel status {prob.status}")
    return {
        "construct": t1 - t0,
        "compile": prob.compilation_time,
        "solve": prob.solver_stats.solve_time,
        "total": t2 - t0,
        "iterations": prob.solver_stats.num_iters,
        "gamma": math.sqrt(max(g.value, 0.0)),
    }


def solve_only(path):
    """The CVXPY user's script: read the dumped model, build, solve, print gamma."""
    with open(path) as f:
        d = json.load(f)
    print(f"{run_cvxpy(d)['gamma']:.8f}")


def wall(cmd):
    """Wall-clock seconds of one fresh process running `cmd` (must exit 0)."""
    t0 = time.perf_counter()
    subprocess.run(cmd, cwd=ROOT, check=True, capture_output=True)
    return time.perf_counter() - t0


def processes(spec, model, tsfc_bin, repeat, tmp):
    """Interleaved fresh-process wall times: (tsfc runs, CVXPY runs)."""
    cv_cmd = [sys.executable, os.path.abspath(__file__), "--solve-only", model]
    ts_cmd = [tsfc_bin, "compile", spec, "--out", os.path.join(tmp, "out")]
    wall(ts_cmd)  # warm-up: page cache for both binaries and imports
    wall(cv_cmd)
    ts, cv = [], []
    for _ in range(repeat):
        ts.append(wall(ts_cmd))
        cv.append(wall(cv_cmd))
    return ts, cv


def med(runs, key):
    return statistics.median(r[key] for r in runs)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--spec", default=os.path.join(ROOT, "specs", "zhang2013_multiobjective.tsf"))
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--json", help="write the comparison as JSON to this path")
    ap.add_argument("--bench-bin", help="path of a built bench-compile (default: cargo run)")
    ap.add_argument("--tsfc-bin", help="path of a built tsfc for the fresh-process table "
                    "(default: target/release/tsfc, or CARGO_TARGET_DIR's)")
    ap.add_argument("--process", type=int, help="fresh-process runs per side (default: --repeat; 0 skips)")
    ap.add_argument("--solve-only", metavar="MODEL", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.solve_only:
        solve_only(args.solve_only)
        return
    global BENCH_BIN
    BENCH_BIN = args.bench_bin

    d = json.loads(bench_compile("--dump-model", args.spec))
    run_cvxpy(d)  # warm-up (imports, caches)
    # Interleaved: one tsfc run (bench-compile's warm-up, then one timed
    # run), one CVXPY run, and again, so that a change of the machine's load
    # hits both sides alike; medians per side.
    runs, tsfc_runs = [], []
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "tsfc.json")
        for _ in range(args.repeat):
            bench_compile("--repeat", "1", "--no-scaling", "--json", out, args.spec)
            with open(out) as f:
                tsfc_runs.append(json.load(f)["shipped"][0])
            runs.append(run_cvxpy(d))
    tsfc = dict(tsfc_runs[-1])
    tsfc["median_s"] = {k: statistics.median(r["median_s"][k] for r in tsfc_runs)
                        for k in tsfc_runs[0]["median_s"]}
    tsfc["runs_s"] = [r["median_s"] for r in tsfc_runs]
    data = build(d)[0].get_problem_data(cp.CLARABEL)[0]
    cv = {k: med(runs, k) for k in ("construct", "compile", "solve", "total")}
    cv["iterations"] = runs[-1]["iterations"]
    cv["gamma"] = runs[-1]["gamma"]
    cv["rows"], cv["unknowns"] = data["A"].shape
    t = tsfc["median_s"]
    gamma_t = tsfc["hinf_gamma"]
    rel = abs(gamma_t - cv["gamma"]) / abs(cv["gamma"])
    speedup = cv["total"] / t["total"]
    overhead = 100 * (t["total"] - t["solve"]) / t["total"]

    print(f"spec: {os.path.relpath(args.spec, ROOT)}, {len(d['rules'])} rules; medians of {args.repeat} interleaved runs (s)\n")
    print("| | construct/parse+model | compile/build | solve (Clarabel) | certify | total | gamma |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    print(f"| CVXPY {cp.__version__} + Clarabel | {cv['construct']:.4f} | {cv['compile']:.4f} | "
          f"{cv['solve']:.4f} | - | {cv['total']:.4f} | {cv['gamma']:.8f} |")
    print(f"| tsfc | {t['parse'] + t['model']:.4f} | {t['build']:.4f} | {t['solve']:.4f} | "
          f"{t['certify']:.4f} | {t['total']:.4f} | {gamma_t:.8f} |")
    print()
    print(f"problem size: tsfc {tsfc['problem']['rows']} rows x {tsfc['problem']['scalar_unknowns']} unknowns; "
          f"CVXPY {cv['rows']} rows x {cv['unknowns']} unknowns; "
          f"iterations: tsfc {tsfc.get('iterations', '?')}, CVXPY {cv['iterations']}")
    goals = [
        ("tsfc pipeline >= 15x faster than CVXPY construct+solve, in process", speedup >= 15, f"{speedup:.2f}x"),
        ("tsfc overhead (total - solve) < 10% of total", overhead < 10, f"{overhead:.1f}%"),
        ("gamma agrees to 1e-5 relative", rel <= 1e-5, f"{rel:.2e}"),
    ]
    nproc = args.repeat if args.process is None else args.process
    if nproc > 0:
        target = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
        tsfc_bin = args.tsfc_bin or os.path.join(target, "release", "tsfc")
        with tempfile.TemporaryDirectory() as tmp:
            model = os.path.join(tmp, "model.json")
            with open(model, "w") as f:
                json.dump(d, f)
            ts, cvp = processes(args.spec, model, tsfc_bin, nproc, tmp)
        e2e = statistics.median(cvp) / statistics.median(ts)
        print()
        print(f"end to end, fresh processes (wall s, medians of {nproc} interleaved runs):")
        print(f"| `python3 compare_cvxpy.py --solve-only` (start, import cvxpy, build, solve) | "
              f"{statistics.median(cvp):.4f} | runs {', '.join(f'{v:.3f}' for v in cvp)} |")
        print(f"| `tsfc compile` (parse .. certify, code and report written) | "
              f"{statistics.median(ts):.4f} | runs {', '.join(f'{v:.3f}' for v in ts)} |")
        goals.insert(1, ("tsfc compile >= 15x faster than the CVXPY script, fresh processes",
                         e2e >= 15, f"{e2e:.2f}x"))
        tsfc["process_s"], cv["process_s"], tsfc["process_speedup"] = ts, cvp, e2e
    for name, ok, value in goals:
        print(f"{'MET   ' if ok else 'MISSED'} {name}: {value}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"spec": os.path.relpath(args.spec, ROOT), "repeat": args.repeat, "cvxpy": cv, "tsfc": tsfc,
                       "speedup": speedup, "overhead_pct": overhead, "gamma_rel_diff": rel}, f, indent=2)


if __name__ == "__main__":
    main()
