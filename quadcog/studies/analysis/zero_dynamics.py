"""Zero dynamics of the outputs y = [z, phi, theta, psi], computed from the generated model.

Holding y = y0 (constant) means y_dot = 0 and y_ddot = 0. Away from the Euler singularity
y_dot = 0 gives nu2 = [p, q, r] = 0 and fixes w by z_dot = 0; the input that keeps y_ddot = 0 is
U* = alpha^{-1} (-b) ('decoupling' and 'drift' of the generated model). The states left free,
zeta = [x, y, u, v], obey zeta_dot = rows [x, y, u, v] of the generated 'dynamics' at
(x(zeta), U*(zeta)): that vector field is built here as a CasADi expression and linearized by
automatic differentiation.

Hand analysis (checked numerically below): with nu2 = 0 the translational rows of
M nu_dot + C nu + D nu + g = B_u U read m nu1_dot + D_1 nu1 + R^T [0, 0, m g] = [0, 0, U1]:
the r_G terms of M (-m S(r_G) nu2_dot), of C (all multiplied by nu2) and of g (only in the moment
rows) drop out. r_G enters only the moment rows, which fix U2..U4. So the zero dynamics do not
depend on r_G, at level or at any tilt the outputs are held at; what depends on r_G is the input
that holds them, and the internal dynamics when the outputs move (nu2 != 0).
"""
from collections.abc import Sequence
import os
from typing import Any

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import solve_ivp

from quadcog.codegen.fastcall import evaluate
from quadcog.controllers.decoupling import decoupled_input
from quadcog.errors import QuadcogError
from quadcog.files import save_figure
from quadcog.model.conventions import IDX, N_PARAM, N_STATE, NU, OUTPUT_ROWS, R_G
from quadcog.model.functions import Model, load
from quadcog.model.parameters import check_parameters, with_cog
from quadcog.vehicles.vehicle import default_parameters

__all__ = ["ZETA_ROWS", "ZETA_NAMES", "DEFAULT_OFFSETS", "DEFAULT_ATTITUDES",
           "zero_dynamics_function", "relative_equilibrium", "zero_dynamics_eigenvalues",
           "rg_sensitivity", "nonlinear_check", "zero_dynamics_study", "plot_zero_dynamics"]

ZETA_ROWS = [0, 1, 6, 7]           # x, y, u, v in the state
ZETA_NAMES = ("x", "y", "u", "v")

_cache: dict[int, tuple[ca.Function, ca.Function]] = {}


def zero_dynamics_function(model: Model | None = None) -> tuple[ca.Function, ca.Function]:
    """The zero-dynamics vector field and its Jacobians as CasADi Functions.

    The first is (zeta (4), y0 (4), p (14)) -> (zeta_dot (4), U* (4), residual (10)):
    zeta = [x, y (m), u, v (m/s)]; y0 = [z0 (m), phi0, theta0, psi0 (rad)]; p the 14
    parameters. zeta_dot in m/s and m/s^2; U* the input that holds the outputs (N, N m).
    residual stacks what must vanish on the zero-dynamics manifold: y_dot (4), y_ddot (4, from
    alpha U* + b), the consistency of the generated w_dot with d/dt of w(zeta) (1), and
    |nu2_dot| (1), so a nonzero residual means the manifold is not invariant.

    Parameters
    ----------
    model : quadcog.model.functions.Model, optional
        The generated model (default ``quadcog.load()``).

    Returns
    -------
    tuple of (casadi.Function, casadi.Function)
        The vector field above, and (zeta, y0, p) -> (A_zd (4, 4) = d zeta_dot / d zeta,
        dzeta_dot_dr (4, 3), dU_dr (4, 3)). Cached per model.
    """
    model = model or load()
    key = id(model)
    if key in _cache:
        return _cache[key]
    f = model.casadi_function("dynamics")
    alpha, drift = model.casadi_function("decoupling"), model.casadi_function("drift")
    zeta, y0, p = ca.SX.sym("zeta", 4), ca.SX.sym("y0", 4), ca.SX.sym("p", N_PARAM)
    w = ca.SX.sym("w")
    zero3 = ca.SX.zeros(3)
    x_w = ca.vertcat(zeta[0], zeta[1], y0, zeta[2], zeta[3], w, zero3)
    z_dot = f(x_w, ca.SX.zeros(4), p)[2]                 # affine in w: a + b w
    b_w = ca.jacobian(z_dot, w)
    a_w = ca.substitute(z_dot, w, ca.SX(0))
    w_star = -a_w / b_w
    x = ca.substitute(x_w, w, w_star)
    U = decoupled_input(alpha(x, p), -drift(x, p))     # as the laws solve it
    xdot = f(x, U, p)
    zeta_dot = xdot[ZETA_ROWS]
    w_rate = ca.jtimes(w_star, zeta, zeta_dot)
    residual = ca.vertcat(xdot[list(OUTPUT_ROWS)], alpha(x, p) @ U + drift(x, p),
                          xdot[8] - w_rate, ca.norm_2(xdot[NU][3:]))
    fn = ca.Function("zero_dynamics", [zeta, y0, p], [zeta_dot, U, residual],
                     ["zeta", "y0", "p"], ["zeta_dot", "U", "residual"])
    jac = ca.Function("zero_dynamics_jacobians", [zeta, y0, p],
                      [ca.jacobian(zeta_dot, zeta), ca.jacobian(zeta_dot, p[R_G]),
                       ca.jacobian(U, p[R_G])],
                      ["zeta", "y0", "p"], ["A_zd", "dzeta_dot_dr", "dU_dr"])
    _cache[key] = (fn, jac)
    return fn, jac


def relative_equilibrium(p: NDArray[np.float64], y0: NDArray[np.float64],
                         model: Model | None = None,
                         tol: float = 1e-13) -> NDArray[np.float64]:
    """The zero-dynamics equilibrium velocity [u*, v*] with the outputs held at y0.

    At level attitude this is [0, 0] (hover); tilted, the held attitude accelerates the
    vehicle sideways until drag balances it: a steady drift (positions change, velocities do
    not), by Newton's method.

    Parameters
    ----------
    p : (14,) numpy.ndarray
        Parameters.
    y0 : (4,) numpy.ndarray
        Held outputs [z0 (m), phi0, theta0, psi0 (rad)].
    model : quadcog.model.functions.Model, optional
        The generated model (default ``quadcog.load()``).
    tol : float
        Largest |[u_dot, v_dot]| accepted [m/s^2].

    Returns
    -------
    (4,) numpy.ndarray
        zeta* = [0, 0, u*, v*] (m, m, m/s, m/s).

    Raises
    ------
    quadcog.errors.QuadcogError
        When Newton's method does not converge in 50 steps.
    """
    fn, jac = zero_dynamics_function(model)
    zeta = np.zeros(4)
    for _ in range(50):
        zd = np.array(fn(zeta, y0, p)[0]).ravel()[2:]
        if np.max(np.abs(zd)) < tol:
            break
        J = np.array(jac(zeta, y0, p)[0])[2:, 2:]
        zeta[2:] -= np.linalg.solve(J, zd)
    else:
        raise QuadcogError(f"no zero-dynamics equilibrium found for y0 = {y0}")
    return zeta


def zero_dynamics_eigenvalues(p: NDArray[np.float64], y0: ArrayLike = (1.0, 0.0, 0.0, 0.0),
                              model: Model | None = None) -> dict[str, Any]:
    """Linearized zero dynamics at the (relative) equilibrium for outputs held at y0.

    Parameters
    ----------
    p : (14,) numpy.ndarray
        Parameters (r_G = p[11:14] in m).
    y0 : (4,) array_like
        Held outputs, as in ``relative_equilibrium``.
    model : quadcog.model.functions.Model, optional
        The generated model (default ``quadcog.load()``).

    Returns
    -------
    dict
        eigenvalues (4,) complex [1/s], A_zd (4, 4) the Jacobian d zeta_dot / d zeta,
        zeta_eq (4,), U_hold (4,) the input on the manifold there [N, N m], residual (max abs
        of the invariance residual) and dzeta_dot_dr (4, 3), the sensitivity of the
        zero-dynamics vector field to r_G at that point (1/s^2, m/s^2 per m).

    Raises
    ------
    quadcog.errors.ParameterError
        When ``p`` is not an admissible parameter vector.
    """
    U: Any                              # the Functions' DM outputs, then their arrays
    A_zd: Any
    p = check_parameters(p)
    fn, jac = zero_dynamics_function(model)
    y0 = np.asarray(y0, dtype=float)
    zeta = relative_equilibrium(p, y0, model)
    _, U, res = fn(zeta, y0, p)
    U = np.array(U).ravel()
    U[np.abs(U) < 1e-12] = 0.0          # round-off of zero moments
    A_zd, dz_dr, _ = jac(zeta, y0, p)
    A_zd = np.array(A_zd)
    eig = np.linalg.eigvals(A_zd)
    return {"eigenvalues": eig[np.lexsort((eig.imag, -eig.real))], "A_zd": A_zd,
            "zeta_eq": zeta, "U_hold": U,
            "residual": float(np.max(np.abs(np.array(res)))),
            "dzeta_dot_dr": np.array(dz_dr)}


def rg_sensitivity(n_points: int = 200, seed: int = 0,
                   model: Model | None = None) -> dict[str, Any]:
    """Largest |d zeta_dot / d r_G| and |d U* / d r_G| over random points of the manifold.

    Samples random zeta (|x|, |y| < 5 m, |u|, |v| < 3 m/s), held outputs y0 (|phi0|,
    |theta0| < 0.5 rad, any psi0) and admissible r_G (|r_G| < 0.09 m) on the default vehicle
    with random drag.

    Parameters
    ----------
    n_points : int
        Random points.
    seed : int
        Seed of the generator.
    model : quadcog.model.functions.Model, optional
        The generated model (default ``quadcog.load()``).

    Returns
    -------
    dict
        n_points, max_dzeta_dot_dr (should be round-off if the zero dynamics do not depend
        on r_G, m/s^2 per m), max_dU_dr (the input does depend on r_G: N m per m), and
        max_residual (manifold invariance).
    """
    rng = np.random.default_rng(seed)
    fn, jac = zero_dynamics_function(model)
    worst_z = worst_u = worst_res = 0.0
    for _ in range(n_points):
        zeta = np.concatenate([rng.uniform(-5, 5, 2), rng.uniform(-3, 3, 2)])
        y0 = np.array([rng.uniform(-2, 2), *rng.uniform(-0.5, 0.5, 2), rng.uniform(-np.pi, np.pi)])
        while True:
            r = rng.uniform(-0.09, 0.09, 3)
            if r @ r < 0.09 ** 2:
                break
        p = default_parameters()
        p[IDX["c_x"]:IDX["c_z"] + 1] = rng.uniform(0.0, 0.5, 3)
        p = check_parameters(with_cog(p, r))
        _, dz, du = jac(zeta, y0, p)
        worst_z = max(worst_z, float(np.max(np.abs(np.array(dz)))))
        worst_u = max(worst_u, float(np.max(np.abs(np.array(du)))))
        worst_res = max(worst_res, float(np.max(np.abs(np.array(fn(zeta, y0, p)[2])))))
    return {"n_points": n_points, "max_dzeta_dot_dr": worst_z, "max_dU_dr": worst_u,
            "max_residual": worst_res}


def _output_tracking_law(model, kp, kd):
    """CasADi Function (x, p, y_d, y_dot_d, y_ddot_d) -> x_dot of the exact FL closed loop
    with the true parameters: U = alpha^{-1} (y_ddot_d - kp e - kd e_dot - b)."""
    f = model.casadi_function("dynamics")
    x, p = ca.SX.sym("x", N_STATE), ca.SX.sym("p", N_PARAM)
    yd, ydd, yddd = ca.SX.sym("yd", 4), ca.SX.sym("ydd", 4), ca.SX.sym("yddd", 4)
    y_dot = f(x, ca.SX.zeros(4), p)[list(OUTPUT_ROWS)]
    v = yddd - ca.DM(kp) * (x[list(OUTPUT_ROWS)] - yd) - ca.DM(kd) * (y_dot - ydd)
    U = decoupled_input(model.casadi_function("decoupling")(x, p),
                        v - model.casadi_function("drift")(x, p))
    return ca.Function("fl_true", [x, p, yd, ydd, yddd], [f(x, U, p)])


def nonlinear_check(r_list: Sequence[Sequence[float]], duration: float = 5.0,
                    u0: Sequence[float] = (0.5, -0.3), moving: bool = False,
                    model: Model | None = None) -> dict[str, Any]:
    """Fly the exact output-tracking closed loop and compare the free states.

    True parameters, so y follows y_d exactly, from level hover at 1 m with body velocity
    [u0, 0]; integrated with scipy DOP853 (rtol 1e-11).

    Parameters
    ----------
    r_list : sequence of (3,) sequence of float
        CoG offsets [m].
    duration : float
        Simulated time [s].
    u0 : (2,) sequence of float
        Initial body velocities u, v [m/s].
    moving : bool
        False holds y_d = [1, 0, 0, 0] (the zero dynamics themselves); True makes the
        attitude move, phi_d = 0.1 (1 - cos 2t), theta_d = -0.08 (1 - cos 3t) rad (internal
        dynamics with nu2 != 0).
    model : quadcog.model.functions.Model, optional
        The generated model (default ``quadcog.load()``).

    Returns
    -------
    dict
        t (N,), zeta (len(r_list), N, 4) [x, y, u, v], analytic (N, 4) the level solution
        u0 exp(-c t / m) etc. (moving=False only), max_spread (largest difference of zeta
        between the r_G cases, m or m/s) and max_error_vs_analytic.
    """
    model = model or load()
    kp, kd = np.array([12.0, 120.0, 120.0, 20.0]), np.array([7.0, 22.0, 22.0, 9.0])
    law = _output_tracking_law(model, kp, kd)
    t_eval = np.linspace(0.0, duration, 501)

    def ref(t):
        if not moving:
            return [1, 0, 0, 0], [0] * 4, [0] * 4
        return ([1, 0.1 * (1 - np.cos(2 * t)), -0.08 * (1 - np.cos(3 * t)), 0],
                [0, 0.2 * np.sin(2 * t), -0.24 * np.sin(3 * t), 0],
                [0, 0.4 * np.cos(2 * t), -0.72 * np.cos(3 * t), 0])

    out = []
    for r in r_list:
        p = check_parameters(with_cog(default_parameters(), r))
        x0 = np.zeros(N_STATE)
        x0[2], x0[6], x0[7] = 1.0, u0[0], u0[1]
        # through kept buffers: a plain call converts to DM and back, 33,000 times a study
        rhs = lambda t, x: evaluate(law, x, p, *ref(t))[0].ravel()
        sol = solve_ivp(rhs, (0, duration), x0, method="DOP853", t_eval=t_eval,
                        rtol=1e-11, atol=1e-12)
        out.append(sol.y[ZETA_ROWS].T)
    zeta = np.array(out)
    p0 = default_parameters()
    decay = np.array([p0[IDX["c_x"]], p0[IDX["c_y"]]]) / p0[IDX["m"]]
    e = np.exp(-np.outer(t_eval, decay))
    analytic = np.hstack([u0 * (1 - e) / decay, u0 * e])
    result = {"t": t_eval, "zeta": zeta, "moving": moving,
              "max_spread": float(np.max(np.abs(zeta - zeta[0]))), "analytic": analytic}
    result["max_error_vs_analytic"] = (float(np.max(np.abs(zeta - analytic)))
                                       if not moving else float("nan"))
    return result


DEFAULT_OFFSETS = ((0.0, 0.0, 0.0), (0.03, 0.02, 0.01), (0.06, 0.06, 0.0), (-0.05, 0.03, 0.02),
                   (0.0, 0.0, 0.05), (0.08, -0.04, 0.0))
DEFAULT_ATTITUDES = ((1.0, 0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.7), (1.0, 0.15, -0.1, 0.0))


def zero_dynamics_study(offsets: Sequence[Sequence[float]] = DEFAULT_OFFSETS,
                        attitudes: Sequence[Sequence[float]] = DEFAULT_ATTITUDES,
                        model: Model | None = None) -> dict[str, Any]:
    """Everything reported about the zero dynamics.

    Parameters
    ----------
    offsets : sequence of (3,) sequence of float
        CoG offsets r_G [m].
    attitudes : sequence of (4,) sequence of float
        Held outputs y0 = [z0 (m), phi0, theta0, psi0 (rad)].
    model : quadcog.model.functions.Model, optional
        The generated model (default ``quadcog.load()``).

    Returns
    -------
    dict
        Per (y0, r_G): the eigenvalues [1/s], the equilibrium velocity and the holding
        input; the paper's eq. 7 values {0, 0, -c_x/m, -c_y/m}; the largest eigenvalue
        difference from r_G = 0 [1/s]; an anisotropic-drag vehicle (c = [0.1, 0.2, 0.3]) to
        show that the tilt can change the eigenvalues while r_G does not; the random-point
        sensitivity (``rg_sensitivity``); and the nonlinear simulations
        (``nonlinear_check``) with held and with moving outputs.
    """
    model = model or load()
    p0 = default_parameters()
    expected = [0.0, 0.0, -p0[IDX["c_x"]] / p0[IDX["m"]], -p0[IDX["c_y"]] / p0[IDX["m"]]]
    cases = []
    for label, base, rs in (("default drag", p0, offsets),
                            ("anisotropic drag c = [0.1, 0.2, 0.3]",
                             default_parameters(c_x=0.1, c_y=0.2, c_z=0.3), offsets[:3])):
        for y0 in attitudes:
            ref_eig = None
            for r in rs:
                zd = zero_dynamics_eigenvalues(with_cog(base, r), y0, model)
                if ref_eig is None:
                    ref_eig = zd["eigenvalues"]
                diff = float(np.max(np.abs(zd["eigenvalues"] - ref_eig)))
                cases.append({"vehicle": label, "y0": list(y0), "r_G": list(r),
                              "eigenvalues": zd["eigenvalues"],
                              "max_diff_from_r0": diff,
                              "zeta_eq": zd["zeta_eq"], "U_hold": zd["U_hold"],
                              "residual": zd["residual"],
                              "max_dzeta_dot_dr": float(np.max(np.abs(zd["dzeta_dot_dr"])))})
    held = nonlinear_check(offsets, moving=False, model=model)
    moving = nonlinear_check(offsets, moving=True, model=model)
    return {"expected_r0": expected, "cases": cases, "offsets": [list(r) for r in offsets],
            "max_eig_diff_over_r_G": max(c["max_diff_from_r0"] for c in cases),
            "sensitivity": rg_sensitivity(model=model),
            "nonlinear_held": held, "nonlinear_moving": moving}


def plot_zero_dynamics(study: dict[str, Any], path: str | os.PathLike[str]) -> None:
    """Save the nonlinear check of ``zero_dynamics_study`` (held vs moving outputs).

    Top row the body velocity u(t) per r_G, bottom row its difference from r_G = 0.

    Parameters
    ----------
    study : dict
        The result of ``zero_dynamics_study``.
    path : str or os.PathLike
        The PNG to write.
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(2, 2, figsize=(12, 7.5), sharex=True)
    offsets = study["offsets"]
    for col, key, title in ((0, "nonlinear_held", "outputs held at level hover (zero dynamics)"),
                            (1, "nonlinear_moving",
                             r"outputs moving: $\phi_d, \theta_d$ oscillate (internal dynamics)")):
        d = study[key]
        ax, bx = axes[0, col], axes[1, col]
        for k, r in enumerate(offsets):
            ls = "-" if k == 0 else "--"
            lbl = f"r_G = {np.round(r, 3).tolist()} m"
            ax.plot(d["t"], d["zeta"][k, :, 2], ls, color=f"C{k}", lw=2 if k == 0 else 1.2,
                    label=lbl)
            if k:
                bx.plot(d["t"], d["zeta"][k, :, 2] - d["zeta"][0, :, 2], color=f"C{k}",
                        lw=1.2, label=lbl)
        if not d["moving"]:
            ax.plot(d["t"], d["analytic"][:, 2], "k:", lw=2,
                    label=r"$u_0 e^{-c_x t/m}$ (paper eq. 7)")
        ax.set_ylabel("body velocity u (m/s)")
        ax.set_title(f"{title}\nmax spread of x, y, u, v over r_G: {d['max_spread']:.2e}")
        bx.set_ylabel(r"u(r_G) - u(r_G = 0) (m/s)")
        bx.set_xlabel("time (s)")
        for a in (ax, bx):
            a.grid(True, alpha=0.3)
    # one legend for all four panels, below them: never over a curve
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=8, frameon=False)
    fig.suptitle("Free states of the exact output-tracking loop (true parameters, "
                 "start u, v = 0.5, -0.3 m/s)")
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    save_figure(fig, path, "zero dynamics plot", dpi=120)
    plt.close(fig)
