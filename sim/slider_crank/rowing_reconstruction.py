"""Reconstruction of paper 003's unpublished desired effort F_d, and an emulation of the solver it really ran.

The paper's cost (its Table 6) is f(L2, L3) = mean_i (F_d,i − k x_i)², k = 244 N/mm, x_i = L2 cos t_i +
√(L3² − L2² sin² t_i) at t = 0:0.1:2π (63 angles, 0 to 6.2 rad), F_d read from a file and multiplied by 1000.
The file is not published.  Its iteration log (fminunc, from [1, 5]) pins it down:

* f at the start, the first step length α1 = 1/‖∇f‖∞ and f after that step give two equations plus a check for
  F_d = k x(θ; L2*, L3*); they give L2* = 3.27869, L3* = 13.52459 mm, i.e. L2* = (4100 − 2500)/(2k) and
  L3* = (4100 + 2500)/(2k): the effort swings between 2.5 kN (θ = 180°) and 4.1 kN (θ = 0°);
* the final error 8.25e-4 N² is not zero: it is the rounding of F_d to 0.1 N (the file in kN with 4 decimals,
  hence the ×1000), whose mean square is ≈ 0.1²/12 = 8.3e-4 N².

:func:`desired_effort` rebuilds that file; :func:`fminunc_log` replays the solver (BFGS quasi-Newton with
forward-difference gradients, MATLAB's fminunc default) so that a test can compare every line of the printed log.
"""

from __future__ import annotations

import numpy as np

#: Spring stiffness (N/mm).
K_N_PER_MM = 244.0
#: Effort extremes of the reconstructed F_d (N): at θ = 0 (slider furthest) and θ = 180°.
F_MAX_N = 4100.0
F_MIN_N = 2500.0
#: Decimals of the F_d file in kN.
DECIMALS_KN = 4
#: The design generating F_d (mm).
GENERATING_DESIGN = ((F_MAX_N - F_MIN_N) / (2 * K_N_PER_MM), (F_MAX_N + F_MIN_N) / (2 * K_N_PER_MM))
#: The paper's iteration log: (func-count, f (N²), step size, first-order optimality), start [1, 5] mm.
PAPER_LOG = ((3, 4.33715e6, None, 1.01e6), (6, 3.38903e6, 9.92098e-07, 8.85e5), (9, 2036.61, 1.0, 1.57e4),
             (12, 553.019, 1.0, 8.3e3), (15, 0.286468, 1.0, 263.0), (18, 0.00149801, 1.0, 12.4),
             (21, 0.000825424, 1.0, 0.00274))
PAPER_START = (1.0, 5.0)


def paper_angles() -> np.ndarray:
    """Crank angles of the paper's cost function, t = 0:0.1:2π (rad): 63 values, 0 to 6.2."""
    return 0.1 * np.arange(63)


def effort(l2: float, l3: float, theta: np.ndarray, k: float = K_N_PER_MM) -> np.ndarray:
    """Spring effort F = k x(θ) (N) of the in-line slider-crank, x = l2 cos θ + √(l3² − l2² sin² θ) in mm."""
    s = np.sin(theta)
    return k * (l2 * np.cos(theta) + np.sqrt(l3 * l3 - (l2 * s) ** 2))


def desired_effort() -> tuple[np.ndarray, np.ndarray]:
    """The reconstructed F_d file: angles (rad) and F_d in kN rounded to :data:`DECIMALS_KN` decimals."""
    theta = paper_angles()
    return theta, np.round(effort(*GENERATING_DESIGN, theta) / 1000.0, DECIMALS_KN)


def mse(design: np.ndarray, theta: np.ndarray, f_d: np.ndarray) -> float:
    """The paper's cost (N²): mean square of F_d − k x over the angles."""
    return float(np.mean((f_d - effort(design[0], design[1], theta)) ** 2))


def fminunc_log(theta: np.ndarray, f_d: np.ndarray, start: tuple[float, float] = PAPER_START,
                iterations: int = 6) -> list[tuple[int, float, float | None, float]]:
    """Replay fminunc's quasi-Newton method on the paper's cost, in the format of its printed log.

    BFGS on the inverse Hessian, started from the identity scaled after the first step (yᵀs/yᵀy); the first step
    along −∇f has length α1 = 1/‖∇f‖∞, later ones the full quasi-Newton step (the log shows step size 1);
    gradients by forward differences with step √eps·max(|x|, 1), so each iteration costs 3 evaluations.

    Returns
    -------
    list of (func-count, f, step size, first-order optimality ‖∇f‖∞)
    """
    eps = np.sqrt(np.finfo(float).eps)

    def grad(x, fx):
        g = np.empty(2)
        for j in range(2):
            e = x.copy()
            e[j] += eps * max(abs(x[j]), 1.0)
            g[j] = (mse(e, theta, f_d) - fx) / (e[j] - x[j])
        return g

    x = np.array(start, dtype=float)
    fx = mse(x, theta, f_d)
    g = grad(x, fx)
    h_inv = np.eye(2)
    log = [(3, fx, None, float(np.max(np.abs(g))))]
    for it in range(iterations):
        alpha = 1.0 / np.max(np.abs(g)) if it == 0 else 1.0
        x_new = x - alpha * (h_inv @ g)
        f_new = mse(x_new, theta, f_d)
        g_new = grad(x_new, f_new)
        s, y = x_new - x, g_new - g
        if it == 0:
            h_inv = h_inv * (y @ s) / (y @ y)
        rho = 1.0 / (y @ s)
        v = np.eye(2) - rho * np.outer(s, y)
        h_inv = v @ h_inv @ v.T + rho * np.outer(s, s)
        x, fx, g = x_new, f_new, g_new
        log.append((3 * (it + 2), fx, alpha, float(np.max(np.abs(g)))))
    return log


def write_desired_effort(path) -> None:
    """Write the reconstructed F_d as CSV: ``theta_rad,fd_kN`` (the data file of studies/rowing)."""
    theta, fd = desired_effort()
    lines = ["theta_rad,fd_kN"] + [f"{t:.1f},{f:.{DECIMALS_KN}f}" for t, f in zip(theta, fd, strict=True)]
    with open(path, "w") as fh:
        fh.write("\n".join(lines) + "\n")
