"""The adaptive design checked: the error-model matrices, and the Lyapunov function
V = e_s^T P e_s + r_tilde^T Gamma^{-1} r_tilde along simulated runs (r_tilde = r_hat - r_G).

In continuous time, with the exact error model e_s_dot = A e_s + B_true Phi r_tilde and the
update r_hat_dot = -Gamma Phi^T B^T P e_s, a constant r_G gives
V_dot = -e_s^T Q e_s + 2 e_s^T P (B_true - B) Phi r_tilde. The last term (``mismatch``) is zero
only when the law's B equals B_true = [0; H M(r_G)^{-1}]; the law uses M_hat = M(r_hat).
"""
from collections.abc import Collection, Sequence
import os
from typing import Any

import casadi as ca
import numpy as np

from quadcog.controllers import AdaptiveFeedbackLinearization
from quadcog.files import save_figure
from quadcog.model.conventions import N_STATE
from quadcog.sim.divergence import Limits
from quadcog.sim.flight import simulate
from quadcog.sim.result import SimulationResult
from quadcog.sim.timeline import CogProfile
from quadcog.studies.analysis.adaptive_variants import (
    OracleAdaptive,
    OracleBMixin,
    OracleOutputRegulationAdaptive,
    OutputRegulationAdaptive,
)
from quadcog.trajectories.analytic import REF_SIZE

__all__ = ["STEP_TIME", "STEP_R", "FAR", "design_checks", "lyapunov_along", "lyapunov_summary",
           "variants", "lyapunov_study", "plot_lyapunov"]

STEP_TIME = 1.0                        # s
STEP_R = (0.06, 0.06, 0.0)             # m, the Fig. 6 scenario
FAR = Limits(max_position_error=1e6)   # without a position loop x, y drift (zero dynamics)


def design_checks(ctl: AdaptiveFeedbackLinearization | None = None) -> dict[str, Any]:
    """Checks of the error-model design of an AdaptiveFeedbackLinearization.

    Parameters
    ----------
    ctl : quadcog.controllers.AdaptiveFeedbackLinearization, optional
        Default: the default design.

    Returns
    -------
    dict
        eig_A (8,) complex [1/s] and max_real_eig_A; P_asymmetry = max|P - P^T|; eig_P (8,)
        (its smallest must be > 0); lyapunov_residual = max|A^T P + P A + Q| and its ratio
        to max|Q|; gamma (3,) the diagonal of Gamma; kp [1/s^2], kd [1/s] (4,) the output
        PD gains that make A.
    """
    ctl = ctl or AdaptiveFeedbackLinearization()
    A, P, Q = ctl.A_error, ctl.P, ctl.Q
    eig_A = np.linalg.eigvals(A)
    res = np.max(np.abs(A.T @ P + P @ A + Q))
    return {"eig_A": eig_A[np.argsort(eig_A.real)], "max_real_eig_A": float(eig_A.real.max()),
            "P_asymmetry": float(np.max(np.abs(P - P.T))),
            "eig_P": np.linalg.eigvalsh(0.5 * (P + P.T)),
            "lyapunov_residual": float(res),
            "lyapunov_residual_relative": float(res / np.max(np.abs(Q))),
            "gamma": np.copy(ctl.gamma), "kp": ctl.kp.copy(), "kd": ctl.kd.copy()}


def _error_function(ctl):
    """CasADi Function (x, ref, r_hat, r_true) -> (e_s (8), mismatch (1)), evaluated with the
    base class law (B at the estimate), whatever the variant."""
    x, ref = ca.SX.sym("x", N_STATE), ca.SX.sym("ref", REF_SIZE)
    rh, rt = ca.SX.sym("r_hat", 3), ca.SX.sym("r_true", 3)
    parts = lambda r: AdaptiveFeedbackLinearization.parts(ctl, x, ref, r)
    _, e_s, Phi, B = parts(rh)
    B_true = parts(rt)[3]
    mismatch = 2 * e_s.T @ ca.DM(ctl.P) @ (B_true - B) @ Phi @ (rh - rt)
    return ca.Function("lyapunov_terms", [x, ref, rh, rt], [e_s, mismatch])


def lyapunov_along(ctl: AdaptiveFeedbackLinearization,
                   res: SimulationResult) -> dict[str, Any]:
    """V and its parts along a run of an adaptive controller.

    Parameters
    ----------
    ctl : quadcog.controllers.AdaptiveFeedbackLinearization
        The controller flown (or a variant of ``variants``).
    res : quadcog.sim.result.SimulationResult
        Its run: uses res.x (N, 12), res.ref (N, 14), res.r_hat (N, 3) and the true CoG
        res.r_G (N, 3).

    Returns
    -------
    dict
        (N,) arrays: t [s], V, V_e = e_s^T P e_s, V_r = r_tilde^T Gamma^{-1} r_tilde (V in
        the units of P e_s^2, i.e. m^2 and rad^2 mixed: V is a number), the continuous-time
        rate terms minus_eQe = -e_s^T Q e_s and mismatch [1/s; zero for the oracle variants,
        whose law uses the true B], and e_s (N, 8).
    """
    fn = _error_function(ctl).map(res.t.size)
    E, mis = fn(res.x.T, res.ref.T, res.r_hat.T, res.r_G.T)
    E, mis = np.array(E).T, np.array(mis).ravel()
    if isinstance(ctl, OracleBMixin):
        mis = np.zeros_like(mis)
    rt = res.r_hat - res.r_G
    V_e = np.einsum("ni,ij,nj->n", E, ctl.P, E)
    V_r = np.sum(rt ** 2 / ctl.gamma, axis=1)
    return {"t": res.t, "V": V_e + V_r, "V_e": V_e, "V_r": V_r, "e_s": E,
            "minus_eQe": -np.einsum("ni,ij,nj->n", E, ctl.Q, E), "mismatch": mis}


def lyapunov_summary(lyap: dict[str, Any], t_step: float = STEP_TIME) -> dict[str, Any]:
    """Numbers of V after the CoG step.

    Parameters
    ----------
    lyap : dict
        The result of ``lyapunov_along``.
    t_step : float
        Time of the step [s].

    Returns
    -------
    dict
        V at the step, the largest rise of V above its running minimum after the step
        (absolute and relative to V(t_step)) and when it peaks, the number of increasing
        samples, the final V, the integral over t >= t_step of the positive part of the
        mismatch rate (what the M_hat approximation can add to V), and the integral of the
        positive part of what the continuous error model does not explain,
        (V_{k+1} - V_k) / dt - (-e_s^T Q e_s + mismatch) at t_k: the neglected derivatives of
        the commanded attitude (position loop) and the 1/dt zero-order hold and Euler update.
    """
    t, V = lyap["t"], lyap["V"]
    k0 = int(np.searchsorted(t, t_step - 1e-12))
    Vp = V[k0:]
    rise = Vp - np.minimum.accumulate(Vp)
    k = int(np.argmax(rise))
    dt = float(t[1] - t[0])
    model_rate = lyap["minus_eQe"][k0:-1] + lyap["mismatch"][k0:-1]
    unexplained = np.diff(Vp) / dt - model_rate
    return {"V_at_step": float(V[k0]), "V_max_after_step": float(Vp.max()),
            "t_V_max": float(t[k0 + int(np.argmax(Vp))]),
            "max_rise": float(rise[k]), "max_rise_relative": float(rise[k] / V[k0]),
            "t_max_rise": float(t[k0 + k]),
            "n_increasing_steps": int(np.sum(np.diff(Vp) > 0)), "n_steps": int(Vp.size - 1),
            "V_final": float(V[-1]),
            "mismatch_positive_integral": float(np.sum(np.maximum(lyap["mismatch"][k0:], 0)) * dt),
            "unexplained_positive_integral": float(np.sum(np.maximum(unexplained, 0)) * dt),
            "dt": dt}


def variants(t_step: float = STEP_TIME, r: Sequence[float] = STEP_R,
             gamma: float = 0.01) -> dict[str, AdaptiveFeedbackLinearization]:
    """The four controllers compared.

    Parameters
    ----------
    t_step : float
        Time of the CoG step [s] (for the oracle variants).
    r : (3,) sequence of float
        The CoG after the step [m] (for the oracle variants).
    gamma : float
        The adaptation gain of all four.

    Returns
    -------
    dict of str to quadcog.controllers.AdaptiveFeedbackLinearization
        {label: controller}; label 'paper' is the project's AdaptiveFeedbackLinearization
        (position loop, B at the estimate).
    """
    kw: dict[str, Any] = dict(gamma=gamma)
    oracle: dict[str, Any] = dict(t_step=t_step, r_after=r)
    return {"paper": AdaptiveFeedbackLinearization(**kw),
            "paper, oracle B": OracleAdaptive(**kw, **oracle),
            "output regulation": OutputRegulationAdaptive(**kw),
            "output regulation, oracle B": OracleOutputRegulationAdaptive(**kw, **oracle)}


def lyapunov_study(duration: float = 20.0, dt: float | None = None,
                   t_step: float = STEP_TIME, r: Sequence[float] = STEP_R,
                   which: Collection[str] | None = None,
                   path: str = "compiled") -> dict[str, dict[str, Any]]:
    """Fly the Fig. 6 scenario with each variant and evaluate V.

    Parameters
    ----------
    duration : float
        Simulated time [s].
    dt : float, optional
        Step [s] (default ``config.defaults["simulate.dt"]``).
    t_step : float
        Time of the CoG step [s].
    r : (3,) sequence of float
        The CoG after the step [m].
    which : collection of str, optional
        Labels of ``variants`` to run (default all).
    path : str
        'compiled' or 'python' (``quadcog.simulate``).

    Returns
    -------
    dict
        {label: {"lyapunov": lyapunov_along(...), "summary": lyapunov_summary(...),
        "metrics": the run's Metrics as a dict}}.
    """
    out = {}
    for label, ctl in variants(t_step, r).items():
        if which is not None and label not in which:
            continue
        res = simulate(ctl, "hover", duration=duration, dt=dt, cog=CogProfile.step(t_step, r),
                       limits=FAR, path=path)
        lyap = lyapunov_along(ctl, res)
        out[label] = {"lyapunov": lyap, "summary": lyapunov_summary(lyap, t_step),
                      "metrics": res.metrics.as_dict()}
    return out


def plot_lyapunov(study: dict[str, dict[str, Any]], path: str | os.PathLike[str],
                  t_step: float = STEP_TIME) -> None:
    """Save V(t) of ``lyapunov_study``: log scale over the run, and two linear zooms after
    the step.

    Parameters
    ----------
    study : dict
        The result of ``lyapunov_study``.
    path : str or os.PathLike
        The PNG to write.
    t_step : float
        Time of the CoG step [s].
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax, bx, cx) = plt.subplots(1, 3, figsize=(17, 4.8),
                                     gridspec_kw={"width_ratios": [1.3, 1, 1]})
    styles = {"paper": ("C0", "-", 2.2), "paper, oracle B": ("C0", ":", 1.8),
              "output regulation": ("C3", "-", 2.2),
              "output regulation, oracle B": ("C3", ":", 1.8)}
    for label, d in study.items():
        c, ls, lw = styles.get(label, ("k", "-", 1))
        L, s = d["lyapunov"], d["summary"]
        ax.semilogy(L["t"], np.where(L["V"] > 0, L["V"], np.nan), color=c, ls=ls, lw=lw,
                    label=f"{label} (max rise {100 * s['max_rise_relative']:.3g} %)")
        for a, lo, width in ((bx, t_step - 0.1, 1.0), (cx, t_step, 0.06)):
            zoom = (L["t"] >= lo) & (L["t"] <= t_step + width)
            a.plot(L["t"][zoom], L["V"][zoom] / s["V_at_step"], color=c, ls=ls, lw=lw,
                   label=label)
    for a in (ax, bx, cx):
        a.axvline(t_step, color="k", lw=1, ls="--", label=f"CoG step at t = {t_step:g} s")
        a.set_xlabel("time (s)")
        a.grid(True, which="both", alpha=0.3)
    ax.set_ylabel(r"$V = e_s^T P e_s + \tilde r^T \Gamma^{-1} \tilde r$")
    ax.set_title("Lyapunov function, CoG step to [6, 6, 0] cm at hover\n"
                 "(V = 0 before the step)")
    # one legend for the three panels, below them: never over a curve
    handles, labels = ax.get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=5, fontsize=8, frameon=False)
    bx.set_ylabel(r"$V / V(t_{step})$")
    bx.set_title("first second after the step")
    cx.set_ylabel(r"$V / V(t_{step})$")
    cx.set_title("first 60 ms after the step:\nV above 1 means V increased")
    cx.axhline(1.0, color="0.5", lw=0.8)
    cx.set_ylim(0.55, 1.12)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    save_figure(fig, path, "Lyapunov plot", dpi=120)
    plt.close(fig)
