#!/usr/bin/env python3
"""Optional feasibility sanity check of the objectives chosen in the specs
(needs cvxpy: `pip install cvxpy`).  Not a reference implementation of tsfc's
synthesis: it only tells whether the decay rates written in the specs are
reasonable, using the LMIs of the LMI reference of the design notes (Tanaka & Wang 2001 conventions) with a
margin eps on strict inequalities.

  zhang:    Zhang & Zeng Theorem 1 (26)-(30): tanaka(s=4) relaxation over the
            pairs of rules that can fire together with the spec's premises,
            H-inf (d -> z = x), input norm mu = 0.01 for the paper's x0,
            minimise gamma^2 for several decay rates a.
  pendulum: basic relaxation, stability + decay rate alpha (bisection).
"""
import itertools
import math
import sys

import cvxpy as cp
import numpy as np

EPS = 1e-7


def He(M):
    return M + M.T


def solve(cons, obj=None):
    p = cp.Problem(cp.Minimize(obj if obj is not None else 0), cons)
    for kw in (dict(solver=cp.CLARABEL), dict(solver=cp.SCS, max_iters=50000, eps=1e-8)):
        try:
            p.solve(**kw)
        except Exception:  # noqa: BLE001  (Clarabel sometimes stops on badly scaled data)
            continue
        if p.status in ("optimal", "infeasible"):
            break
    return p.status, p.value


def zhang(a, mu=0.01, s=4):
    J = np.array([[127, 1.8, -3.4], [1.8, 117, -2.3], [-3.4, -2.3, 210]])
    Ji = np.linalg.inv(J)

    def Phi(v):
        return np.array([[0, v[2], -v[1]], [-v[2], 0, v[0]], [v[1], -v[0], 0]])

    pts = [(c, d) for c in (0.0, 0.1, -0.1) for d in (0.0, 0.15, -0.15)]
    A = []
    for c, d in pts:
        w, r = np.full(3, c), np.full(3, d)
        A.append(np.block([[-Ji @ Phi(w) @ J, np.zeros((3, 3))],
                           [0.5 * (np.eye(3) + np.outer(r, r)), 0.5 * Phi(w)]]))
    B = np.vstack([Ji, np.zeros((3, 3))])
    D, C = B, np.eye(6)
    n, m, q, r = 6, 3, 3, 9
    X = cp.Variable((n, n), symmetric=True)
    Y = cp.Variable((n, n), symmetric=True)
    M = [cp.Variable((m, n)) for _ in range(r)]  # M_j = F_j X  (F = -K)
    g = cp.Variable()
    x0 = np.array([0.08, -0.05, 0.1, 0.12, 0.06, -0.08])
    I = np.eye

    def Ups(i, j):
        return He(A[i] @ X + B @ M[j])

    def adj(i, j):  # can rules i and j fire together with the mean premises?
        (ci, di), (cj, dj) = pts[i], pts[j]
        return abs(ci - cj) <= 0.1 + 1e-12 and abs(di - dj) <= 0.15 + 1e-12

    cons = [X >> EPS * I(n), Y >> 0]
    N = n + q + n

    def hinf(Qs):  # Q block of the bounded real lemma around a (symmetrised) Upsilon
        return cp.bmat([[Qs, D, X @ C.T], [D.T, -g * I(q), np.zeros((q, n))], [C @ X, np.zeros((n, q)), -I(n)]])

    Yb = cp.bmat([[Y, np.zeros((n, q + n))], [np.zeros((q + n, n)), np.zeros((q + n, q + n))]])
    for i in range(r):
        # (26) decay: Q_ii + (s-1) Y < 0
        cons.append(Ups(i, i) + 2 * a * X + (s - 1) * Y << -EPS * I(n))
        # (28) H-inf for i = j
        cons.append(hinf(Ups(i, i)) << -EPS * I(N))
        # (30) input norm
        cons.append(cp.bmat([[X, M[i].T], [M[i], mu**2 * I(m)]]) >> 0)
    for i, j in itertools.combinations(range(r), 2):
        if not adj(i, j):
            continue
        S = (Ups(i, j) + Ups(j, i)) / 2
        cons.append(S + 2 * a * X - Y << 0)  # (27)
        cons.append(hinf(S) << -EPS * I(N))  # (28) i < j
    cons.append(cp.bmat([[np.ones((1, 1)), x0[None, :]], [x0[:, None], X]]) >> 0)  # (29)
    st, val = solve(cons, g)
    return st, (math.sqrt(val) if val is not None and val > 0 else val)


def pendulum(alpha):
    g, m, Mc, l = 9.8, 2.0, 8.0, 0.5
    a = 1 / (m + Mc)
    beta = math.cos(math.radians(88))
    A1 = np.array([[0, 1], [g / (4 * l / 3 - a * m * l), 0]])
    B1 = np.array([[0], [-a / (4 * l / 3 - a * m * l)]])
    A2 = np.array([[0, 1], [2 * g / (math.pi * (4 * l / 3 - a * m * l * beta**2)), 0]])
    B2 = np.array([[0], [-a * beta / (4 * l / 3 - a * m * l * beta**2)]])
    A, B = [A1, A2], [B1, B2]
    X = cp.Variable((2, 2), symmetric=True)
    M = [cp.Variable((1, 2)) for _ in range(2)]
    Q = lambda i, j: He(A[i] @ X + B[i] @ M[j]) + 2 * alpha * X  # noqa
    cons = [X >> 1e-3 * np.eye(2), X << 1e3 * np.eye(2),
            Q(0, 0) << -EPS * np.eye(2), Q(1, 1) << -EPS * np.eye(2), Q(0, 1) + Q(1, 0) << -EPS * np.eye(2)]
    st, _ = solve(cons)
    F = [Mi.value @ np.linalg.inv(X.value) for Mi in M] if st == "optimal" else None
    return st, F


if __name__ == "__main__":
    which = sys.argv[1:] or ["zhang", "pendulum"]
    if "pendulum" in which:
        for al in [0.0, 0.5, 1.0, 2.0, 3.0, 5.0]:
            st, F = pendulum(al)
            print(f"pendulum  alpha = {al}: {st}", "" if F is None else f"F1 = {F[0].round(2)}, F2 = {F[1].round(2)}")
    if "zhang" in which:
        for a, mu in [(0.0, 0.01), (0.01, 0.01), (0.0, 1.0), (0.0, 3.0), (0.0, 10.0), (0.01, 10.0), (0.0, 100.0), (0.01, 100.0)]:
            st, gam = zhang(a, mu=mu)
            print(f"zhang  decay a = {a}, mu = {mu}, s = 4: {st}, gamma = {gam}")
