#!/usr/bin/env python3
"""Independent check of the three shipped specs' transcriptions (numpy only).

This does NOT parse the .tsf files (no tsfc parser existed when it was
written): it re-implements, from the papers, the state-dependent matrices the
specs write, evaluates them at each rule's operating point and checks

  * dimensions and that A(x) x (+ B(x) u) reproduces the nonlinear vector
    field of the source (the state-dependent factorisation is exact);
  * every matrix the sources print (pendulum: the textbook A1, B1, A2, B2);
  * Xu & Huang Appendix A: the block-wise reading of the printed 6x3 gain
    arrays (F_i = [rows 1-3 | rows 4-6]) makes every vertex loop A_i + B F_i
    Hurwitz, a plain transpose leaves some unstable; Upsilon > 0;
  * coverage of the premise design of each spec (sum of firing strengths > 0
    on a dense grid of the operating region) and the largest number of rules
    firing at once (the s of Zhang & Zeng's Lemma 1).

Run:  python3 specs/tools/check_models.py      (exit status 1 on a failed check)
"""
import json
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REF = os.path.join(HERE, "..", "reference")
FAILED = []


def check(cond, msg):
    print(("  ok    " if cond else "  FAIL  ") + msg)
    if not cond:
        FAILED.append(msg)


def skew(v):  # skew(a) @ b == cross(a, b)
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]], dtype=float)


def tri(z, a, b, c):
    z = np.asarray(z, dtype=float)
    up = np.where(b > a, (z - a) / (b - a if b > a else 1), 1.0)
    dn = np.where(c > b, (c - z) / (c - b if c > b else 1), 1.0)
    v = np.minimum(up, dn)
    return np.where((z < a) | (z > c), 0.0, np.clip(v, 0, 1))


def trap(z, a, b, c, d):
    z = np.asarray(z, dtype=float)
    up = (z - a) / (b - a) if b > a else np.ones_like(z)
    dn = (d - z) / (d - c) if d > c else np.ones_like(z)
    v = np.minimum(np.minimum(up, 1.0), dn)
    return np.where((z < a) | (z > d), 0.0, np.clip(v, 0, 1))


# --------------------------------------------------------------------------
# 1. Zhang & Zeng: rigid spacecraft, Cayley-Rodrigues, 9 rules
# --------------------------------------------------------------------------
def zhang():
    print("== zhang2013_multiobjective ==")
    J = np.array([[127, 1.8, -3.4], [1.8, 117, -2.3], [-3.4, -2.3, 210]])
    Ji = np.linalg.inv(J)

    def Phi(v):  # eq. (2), transcribed: Phi(v) == -skew(v)
        return np.array([[0, v[2], -v[1]], [-v[2], 0, v[0]], [v[1], -v[0], 0]], dtype=float)

    def A(x):  # the A_i formula under (10), evaluated at the state
        w, r = x[:3], x[3:]
        return np.block([[-Ji @ Phi(w) @ J, np.zeros((3, 3))],
                         [0.5 * (np.eye(3) + np.outer(r, r)), 0.5 * Phi(w)]])

    B = np.vstack([Ji, np.zeros((3, 3))])

    def f_paper(x):  # eqs. (1), (3), (4) with u = d = 0
        w, r = x[:3], x[3:]
        return np.concatenate([-Ji @ Phi(w) @ J @ w,
                               0.5 * (np.eye(3) - Phi(r) + np.outer(r, r)) @ w])

    rng = np.random.default_rng(1)
    err = max(np.abs(A(x) @ x - f_paper(x)).max()
              for x in rng.uniform(-0.3, 0.3, size=(200, 6)))
    check(err < 1e-14, f"A(x) x == paper (1),(3),(4) vector field (max diff {err:.1e})")
    check(np.allclose(Phi(np.array([1., 2, 3])), -skew([1, 2, 3])), "Phi(v) of eq. (2) equals -skew(v)")
    # Sign of the gyroscopic term: paper (1) gives w' = -J^-1 Phi(w) J w = +J^-1 (w x J w);
    # Euler's equation is w' = -J^-1 (w x J w).  Report, do not change.
    w = np.array([0.08, -0.05, 0.1])
    g_paper = -Ji @ Phi(w) @ J @ w
    g_euler = -Ji @ np.cross(w, J @ w)
    print(f"  note  gyroscopic term at w(0): paper (1) {g_paper}, Euler {g_euler}"
          f" -> paper = {np.dot(g_paper, g_euler) / np.dot(g_euler, g_euler):+.3f} x Euler")
    # kinematics (4): 1/2 (I - Phi(rho) + rho rho') = 1/2 (I + skew(rho) + rho rho'), the standard CRP Jacobian
    r = np.array([0.12, 0.06, -0.08])
    check(np.allclose(0.5 * (np.eye(3) - Phi(r) + np.outer(r, r)),
                      0.5 * (np.eye(3) + skew(r) + np.outer(r, r))), "eq. (4) is the standard CRP kinematics")

    cw, cr = [0.0, 0.1, -0.1], [0.0, 0.15, -0.15]
    pts = [(a, b) for a in cw for b in cr]  # paper's order: [0 0],[0 .15],[0 -.15],[.1 0],...
    As = []
    for k, (a, b) in enumerate(pts, 1):
        x = np.array([a] * 3 + [b] * 3)
        Ak = A(x)
        As.append(Ak)
        check(Ak.shape == (6, 6), f"R{k}: w = {a}*[1,1,1], rho = {b}*[1,1,1], A is 6x6, "
                                  f"eig real parts in [{np.linalg.eigvals(Ak).real.min():.4f}, "
                                  f"{np.linalg.eigvals(Ak).real.max():.4f}]")
    check(B.shape == (6, 3), "B = D = [inv(J); 0] is 6x3")
    print(f"  info  max |A_i[3:,:3] - 0.5 I| = {max(np.abs(Ak[3:, :3] - 0.5*np.eye(3)).max() for Ak in As):.5f}"
          " (= 0.5*0.15^2 from rho rho')")

    # Disturbance of Section 4: bound
    t = np.linspace(0, 2 * math.pi / 0.001, 200001)
    d = 1e-5 * np.vstack([1.2 * (3 * np.cos(0.001 * t) + 1),
                          1.5 * (1.5 * np.sin(0.001 * t) + 3 * np.cos(0.001 * t)),
                          1.2 * (3 * np.sin(0.001 * t) + 1)])
    print(f"  info  max ||T_d(t)|| over one orbit = {np.linalg.norm(d, axis=0).max():.3e} N m")

    # Premise design of the spec: wm = mean(w), rm = mean(rho), three sets each.
    def sets_w(z):
        return [trap(z, -10, -10, -0.1, 0), tri(z, -0.1, 0, 0.1), trap(z, 0, 0.1, 10, 10)]

    def sets_r(z):
        return [trap(z, -10, -10, -0.15, 0), tri(z, -0.15, 0, 0.15), trap(z, 0, 0.15, 10, 10)]

    # rule k <-> (wm set, rm set) with set index 0 = zero, 1 = pos, 2 = neg (paper order)
    idx = {0.0: 1, 0.1: 2, -0.1: 0, 0.15: 2, -0.15: 0}

    def strengths(W, R):
        wm, rm = W.mean(axis=-1), R.mean(axis=-1)
        Sw, Sr = sets_w(wm), sets_r(rm)
        return np.stack([Sw[idx[a]] * Sr[idx[b]] for a, b in pts], axis=-1)

    for lim_w, lim_r, label in [(0.1, 0.15, "operating region |w_i|<=0.1, |rho_i|<=0.15"),
                                (1.0, 1.0, "wider box |w_i|<=1, |rho_i|<=1")]:
        gw = np.linspace(-lim_w, lim_w, 9)
        gr = np.linspace(-lim_r, lim_r, 9)
        G = np.stack(np.meshgrid(gw, gw, gw, gr, gr, gr, indexing="ij"), axis=-1).reshape(-1, 6)
        S = strengths(G[:, :3], G[:, 3:])
        tot = S.sum(axis=1)
        nfire = (S > 0).sum(axis=1)
        check(tot.min() > 0, f"coverage on 9^6 grid, {label}: min sum of strengths = {tot.min():.3f}, "
                             f"max rules firing at once = {nfire.max()}")
    check(nfire.max() <= 4, "at most 4 rules fire at once (tanaka s = 4)")

    # The sketch's product-of-components premises: hole at w = [0.1, -0.1, 0]
    def comp_sets(z, c):
        return {"neg": tri(z, -c, -c, 0), "zero": tri(z, -c, 0, c), "pos": tri(z, 0, c, c)}
    name = {0.0: "zero", 0.1: "pos", -0.1: "neg", 0.15: "pos", -0.15: "neg"}
    x = np.array([0.1, -0.1, 0.0, 0.0, 0.0, 0.0])
    tot = 0.0
    for a, b in pts:
        s = 1.0
        for j in range(3):
            s *= comp_sets(x[j], 0.1)[name[a]]
            s *= comp_sets(x[3 + j], 0.15)[name[b]]
        tot += s
    check(tot == 0.0, "the sketch's product-of-components premises leave a hole at w = [0.1, -0.1, 0], rho = 0 "
                      f"(sum of strengths {tot})")
    wm_ = strengths(x[None, :3], x[None, 3:]).sum()
    check(wm_ > 0, f"the spec's mean premises fire there (sum {wm_:.3f})")


# --------------------------------------------------------------------------
# 2. Xu & Huang: quaternion, 7 rules, Appendix A gains
# --------------------------------------------------------------------------
def xu():
    print("== xu2020_event_triggered ==")
    J = np.array([[350, 3, 4], [3, 270, 10], [4, 10, 190]], dtype=float)
    Ji = np.linalg.inv(J)

    def A(x):  # A_i under (7), evaluated at the state
        w, q = x[:3], x[3:]
        return np.block([[-Ji @ skew(w) @ J, np.zeros((3, 3))],
                         [0.5 * math.sqrt(1 - q @ q) * np.eye(3), -0.5 * skew(w)]])

    B = np.vstack([Ji, np.zeros((3, 3))])

    def f(x):  # eqs. (2), (3) with q0 = sqrt(1 - |q|^2) (Remark 1), u = tau = 0
        w, q = x[:3], x[3:]
        q0 = math.sqrt(1 - q @ q)
        return np.concatenate([-Ji @ np.cross(w, J @ w), 0.5 * (q0 * np.eye(3) + skew(q)) @ w])

    rng = np.random.default_rng(2)
    err = 0.0
    for _ in range(200):
        x = np.concatenate([rng.uniform(-1, 1, 3), rng.uniform(-0.56, 0.56, 3)])
        err = max(err, np.abs(A(x) @ x - f(x)).max())
    check(err < 1e-14, f"A(x) x == paper (2),(3) vector field (max diff {err:.1e})")

    pts = [(0, 0), (0, 0.56), (0, -0.56), (0.5, 0), (-0.5, 0), (1, 0.56), (-1, -0.56)]  # Model Rule 1..7
    As = [A(np.array([a] * 3 + [b] * 3, dtype=float)) for a, b in pts]
    for k, ((a, b), Ak) in enumerate(zip(pts, As), 1):
        check(Ak.shape == (6, 6), f"R{k}: w = {a}*[1,1,1], q = {b}*[1,1,1]: A 6x6, "
                                  f"0.5*sqrt(1-|q|^2) = {Ak[3, 0]:.6f}")
    print(f"  info  |q|^2 at the q-vertices = {3 * 0.56**2:.4f} (< 1, so q0 = sqrt(1-|q|^2) is real on the box)")

    ref = json.load(open(os.path.join(REF, "xu2020_appendix_a.json")))
    F_blk = [np.array(F) for F in ref["F"]]
    F_prn = [np.array(P) for P in ref["F_printed_6x3"]]
    for Fb, P in zip(F_blk, F_prn):
        assert Fb.shape == (3, 6) and P.shape == (6, 3)
        assert np.array_equal(Fb, np.hstack([P[:3], P[3:]]))
    # Re-read the paper's OCR text, if given in TSFC_XU_OCR, to confirm the
    # JSON transcription.
    paper = os.environ.get("TSFC_XU_OCR", "")
    if paper and os.path.exists(paper):
        app = open(paper).read().split("Appendix A")[-1]
        ok = True
        for k in range(1, 8):
            j = app.index("\\mathbf{F}_%d = " % k)
            blk = app[j:app.index("\\end{bmatrix}", j)].split("\\begin{bmatrix}")[1]
            P = np.array([[float(v) for v in r.split("&")] for r in blk.split("\\\\")])
            ok &= np.array_equal(P, F_prn[k - 1])
        check(ok, "JSON gains equal the OCR text of Appendix A digit for digit")
    U = np.array(ref["Upsilon"])
    ev = np.linalg.eigvalsh(U)
    check(np.allclose(U, U.T) and ev.min() > 0, f"Upsilon (block-wise reading) symmetric positive definite, "
                                                f"eig = {np.round(ev, 4).tolist()}")

    print("  vertex loops A_i + B F_i (max real part of eigenvalues):")
    worst_b, bad_t = -np.inf, []
    for k, (Ak, Fb, P) in enumerate(zip(As, F_blk, F_prn), 1):
        eb = np.linalg.eigvals(Ak + B @ Fb)
        et = np.linalg.eigvals(Ak + B @ P.T)
        worst_b = max(worst_b, eb.real.max())
        if et.real.max() >= 0:
            bad_t.append(k)
        print(f"    R{k}: block-wise {eb.real.max():+.4f}   transpose {et.real.max():+.4f}")
        print(f"         block-wise eig: {np.array2string(np.sort_complex(eb), precision=4, max_line_width=200)}")
        print(f"         transpose  eig: {np.array2string(np.sort_complex(et), precision=4, max_line_width=200)}")
    check(worst_b < 0, f"block-wise: every A_i + B F_i Hurwitz (max Re = {worst_b:.4f})")
    check(bad_t == [6, 7], f"plain transpose: unstable vertex loops = {bad_t} (lmi-reference.md says 6 and 7)")
    cross = max(np.linalg.eigvals(Ai + B @ Fj).real.max() for Ai in As for Fj in F_blk)
    print(f"  info  all 49 pairs A_i + B F_j (block-wise): max Re eig = {cross:+.4f}")

    # disturbance of Section 4 against tau_bar = 0.01
    t = np.linspace(0, 2000, 400001)
    tau = 1e-3 * np.vstack([-1.5 + 2 * np.cos(0.06 * t) - 0.5 * np.cos(0.2 * t),
                            2 + 1.5 * np.sin(0.06 * t) - 1 * np.cos(0.2 * t),
                            -1.5 + 2 * np.sin(0.06 * t) - 1.5 * np.sin(0.2 * t)])
    mx = np.linalg.norm(tau, axis=0).max()
    check(mx <= 0.01, f"max ||tau(t)|| over 0..2000 s = {mx:.5f} <= tau_bar = 0.01")
    q0 = np.array([-0.3802, 0.2124, 0.5013])
    print(f"  info  initial quaternion norm^2 with q0(0)=0.7477: {0.7477**2 + q0 @ q0:.6f}; "
          f"sqrt(1-|q(0)|^2) = {math.sqrt(1 - q0 @ q0):.4f}")

    # Coverage of the `about` premises (radial Gaussian, default sigma = half the
    # smallest distance between distinct about points of the premise).
    def default_sigma(points):
        P = np.array(points, dtype=float)
        D = [np.linalg.norm(a - b) for i, a in enumerate(P) for b in P[i + 1:] if np.linalg.norm(a - b) > 0]
        return 0.5 * min(D)

    wpts = sorted({a for a, _ in pts})
    qpts = sorted({b for _, b in pts})
    sw = default_sigma([[a] * 3 for a in wpts])
    sq = default_sigma([[b] * 3 for b in qpts])
    print(f"  info  default sigma: w {sw:.4f} (= 0.5*|0.5*[1,1,1]|), q {sq:.4f} (= 0.5*|0.56*[1,1,1]|)")
    g1 = np.linspace(-1, 1, 7)
    g2 = np.linspace(-0.56, 0.56, 7)
    G = np.stack(np.meshgrid(g1, g1, g1, g2, g2, g2, indexing="ij"), axis=-1).reshape(-1, 6)
    W = np.zeros((G.shape[0], 7))
    for k, (a, b) in enumerate(pts):
        dw = ((G[:, :3] - a) ** 2).sum(axis=1)
        dq = ((G[:, 3:] - b) ** 2).sum(axis=1)
        W[:, k] = np.exp(-0.5 * dw / sw**2) * np.exp(-0.5 * dq / sq**2)
    tot = W.sum(axis=1)
    i = tot.argmin()
    check(tot.min() > 0, f"coverage on 7^6 grid of |w_i|<=1, |q_i|<=0.56: min sum of strengths = {tot.min():.3e} "
                         f"at x = {np.round(G[i], 3).tolist()}; all 7 rules fire everywhere (Gaussian support)")


# --------------------------------------------------------------------------
# 3. Inverted pendulum (Wang, Tanaka & Griffin 1996)
# --------------------------------------------------------------------------
def pendulum():
    print("== inverted_pendulum ==")
    g, m, M, l = 9.8, 2.0, 8.0, 0.5
    a = 1.0 / (m + M)
    beta = math.cos(math.radians(88))

    def sinc(v):
        return 1.0 if v == 0 else math.sin(v) / v

    def den(th):
        return 4 * l / 3 - a * m * l * math.cos(th) ** 2

    def A(th, om):
        return np.array([[0, 1], [g * sinc(th) / den(th), -a * m * l * om * math.sin(2 * th) / (2 * den(th))]])

    def Bx(th):
        return np.array([[0], [-a * math.cos(th) / den(th)]])

    def f(th, om, u):  # the nonlinear cart-pole pendulum equation
        return np.array([om, (g * math.sin(th) - a * m * l * om**2 * math.sin(2 * th) / 2 - a * math.cos(th) * u)
                         / (4 * l / 3 - a * m * l * math.cos(th) ** 2)])

    rng = np.random.default_rng(3)
    err = 0.0
    for _ in range(500):
        th, om, u = rng.uniform(-3, 3), rng.uniform(-5, 5), rng.uniform(-100, 100)
        err = max(err, np.abs(A(th, om) @ [th, om] + (Bx(th) * u).ravel() - f(th, om, u)).max())
    check(err < 1e-12, f"A(x) x + B(x) u == nonlinear pendulum equation (max diff {err:.1e})")

    A1 = np.array([[0, 1], [g / (4 * l / 3 - a * m * l), 0]])
    B1 = np.array([[0], [-a / (4 * l / 3 - a * m * l)]])
    A2 = np.array([[0, 1], [2 * g / (math.pi * (4 * l / 3 - a * m * l * beta**2)), 0]])
    B2 = np.array([[0], [-a * beta / (4 * l / 3 - a * m * l * beta**2)]])
    print(f"  info  textbook A1[1,0] = {A1[1, 0]:.6f}, B1[1] = {B1[1, 0]:.6f}, "
          f"A2[1,0] = {A2[1, 0]:.6f}, B2[1] = {B2[1, 0]:.6f}, beta = cos 88 deg = {beta:.6f}")
    d1 = max(np.abs(A(0, 0) - A1).max(), np.abs(Bx(0) - B1).max())
    check(d1 < 1e-12, f"R1 at(theta = 0): A, B == textbook A1, B1 (max diff {d1:.1e})")
    th2 = math.radians(88)
    dB2 = np.abs(Bx(th2) - B2).max()
    check(dB2 < 1e-12, f"R2 at(theta = 88 deg): B == textbook B2 (max diff {dB2:.1e})")
    dA2 = np.abs(A(th2, 0) - A2).max()
    print(f"  note  R2 at(theta = 88 deg): A[1,0] = {A(th2, 0)[1, 0]:.6f} vs textbook {A2[1, 0]:.6f} "
          f"(diff {dA2:.4f}): textbook uses sin(x)/x at 90 deg (2/pi = {2 / math.pi:.6f}) "
          f"but cos at 88 deg; sinc(88 deg) = {sinc(th2):.6f}")
    A2ov = np.array([[0, 1], [g * sinc(math.pi / 2) / (4 * l / 3 - a * m * l * beta**2), 0]])
    check(np.abs(A2ov - A2).max() < 1e-12, "R2 override A = [0, 1; g*sinc(pi/2)/(4l/3 - a m l beta^2), 0] == textbook A2")
    for name, Ak, Bk in [("A1,B1", A1, B1), ("A2,B2", A2, B2)]:
        ctrb = np.hstack([Bk, Ak @ Bk])
        print(f"  info  {name}: open-loop eig {np.linalg.eigvals(Ak).round(4).tolist()}, "
              f"controllable: {np.linalg.matrix_rank(ctrb) == 2}")

    # Memberships: premise s = sinc(theta), near = tri(2/pi, 1, 1), far = trap(-0.25, -0.25, 2/pi, 1)
    z0 = 2 / math.pi
    th = np.linspace(-math.radians(88), math.radians(88), 200001)
    z = np.where(th == 0, 1.0, np.sin(th) / np.where(th == 0, 1, th))
    near = tri(z, z0, 1, 1)
    far = trap(z, -0.25, -0.25, z0, 1)
    tot = near + far
    check(tot.min() > 0 and np.abs(tot - 1).max() < 1e-12,
          f"coverage theta in [-88, 88] deg: sum of strengths in [{tot.min():.6f}, {tot.max():.6f}] "
          "(the two sets form a partition of unity)")
    # sector identity: sin(theta) = h1 * theta + h2 * (2/pi) * theta exactly on |theta| <= 90 deg
    h1 = near / tot
    dev = np.abs(h1 * th + (1 - h1) * z0 * th - np.sin(th)).max()
    check(dev < 1e-12, f"h1*theta + h2*(2/pi)*theta == sin(theta) on |theta|<=88 deg (max diff {dev:.1e})")
    thb = np.linspace(-math.pi, math.pi, 200001)
    zb = np.where(thb == 0, 1.0, np.sin(thb) / np.where(thb == 0, 1, thb))
    totb = tri(zb, z0, 1, 1) + trap(zb, -0.25, -0.25, z0, 1)
    check(totb.min() > 0, f"beyond: some rule fires for all theta in [-180, 180] deg (min sum {totb.min():.3f}); "
                          f"for |theta| >= 90 deg only R2 fires (sinc <= 2/pi), outside the validated sector")
    print(f"  info  at theta = 60 deg: h1 = {float(tri(sinc(math.radians(60)), z0, 1, 1)):.4f}")


if __name__ == "__main__":
    np.set_printoptions(suppress=True)
    zhang()
    xu()
    pendulum()
    print()
    if FAILED:
        print(f"{len(FAILED)} check(s) FAILED")
        sys.exit(1)
    print("all checks passed")
