"""quadcog.studies.analysis: the checks behind the paper's designs, as numbers, tables and figures.

``analyze(out_dir)`` runs four parts and writes PNGs, analysis.json and analysis.md:

1. ``pd_design``: closed-loop eigenvalues, MIMO Bode (singular values) and per-channel margins
   of the cascade PD through python-control (``frequency``: margins and the independent
   eigenvalue check; ``linear``: ``hover_statespace``, the hover linearization as a
   ``control.StateSpace``, and the loop L(s)).
2. ``zero_dynamics``: the zero dynamics of y = [z, phi, theta, psi] from the generated model by
   AD, at several CoG offsets and held attitudes, with a nonlinear simulation check.
3. ``adaptive_design``: the error-model matrices and the Lyapunov function along the Fig. 6
   run, with diagnostic controller variants (``adaptive_variants``).
4. ``failure_map``: tail RMS error of the three controllers over a grid of CoG offsets.
"""
import os
from pathlib import Path
import sys
import time
from typing import Any

import numpy as np

from quadcog import config, validate
from quadcog.errors import InputError
from quadcog.files import RunFiles, check_outputs, creatable_folder, run_stamp
from quadcog.model.conventions import IDX
from quadcog.studies.analysis.adaptive_design import design_checks, lyapunov_study, plot_lyapunov
from quadcog.studies.analysis.analysis_files import write_json, write_latex, write_markdown
from quadcog.studies.analysis.failure_map import (
    THRESHOLD,
    adaptive_failures_vs_projection,
    check_arguments,
    failure_map,
    plot_failure_map,
    save_failure_map,
)
from quadcog.studies.analysis.linear import hover_statespace, loop_statespace
from quadcog.studies.analysis.pd_design import pd_design, plot_sigma
from quadcog.studies.analysis.zero_dynamics import plot_zero_dynamics, zero_dynamics_study
from quadcog.vehicles.vehicle import default_parameters
from quadcog.viz.progress import ProgressBar

__all__ = ["analyze", "hover_statespace", "loop_statespace", "pd_design", "zero_dynamics_study",
           "design_checks", "lyapunov_study", "failure_map"]


def _say(progress, text):
    if progress:
        print(text, file=sys.stderr, flush=True)


def _pd_summary(pd):
    keep = ("phase_margin_deg", "gain_crossover_rad_s", "gain_margin_db", "phase_crossover_rad_s",
            "lower_gain_margin_db", "lower_phase_crossover_rad_s", "eigenvalue_gain_range",
            "eigenvalue_gain_range_db", "channel")
    return {"eigenvalues": pd["eigenvalues"],
            "max_real_eigenvalue": float(pd["eigenvalues"].real.max()),
            "poles": pd["poles"],
            "omega_range": [float(pd["omega"][0]), float(pd["omega"][-1])],
            "margins": [{k: m[k] for k in keep} for m in pd["margins"]],
            **{k: pd[k] for k in ("min_sigma_return_difference",
                                  "min_sigma_return_difference_at_rad_s",
                                  "min_sigma_inverse_return_difference",
                                  "min_sigma_inverse_return_difference_at_rad_s",
                                  "guaranteed_simultaneous_gain_margin_db",
                                  "guaranteed_simultaneous_phase_margin_deg")},
            "sigma_max_L_db_at_1_rad_s": float(20 * np.log10(np.interp(
                1.0, pd["omega"], pd["sigma_L"][:, 0])))}


def _zd_summary(zd):
    sens, held, mov = zd["sensitivity"], zd["nonlinear_held"], zd["nonlinear_moving"]
    unchanged = (zd["max_eig_diff_over_r_G"] < 1e-9 and sens["max_dzeta_dot_dr"] < 1e-9
                 and held["max_spread"] < 1e-6)
    if unchanged:
        finding = ("the zero dynamics do NOT change with r_G (holding the outputs forces "
                   "nu2 = 0, which removes every r_G term from the force rows; "
                   "docs/model.md sec. 4.1). Eigenvalues stay {0, 0, -c_x/m, -c_y/m} for "
                   "every admissible r_G, at level attitude and at any held tilt or heading")
    else:
        finding = ("the zero dynamics DO change with r_G, contrary to docs/model.md sec. 4.1 "
                   "(which must then be corrected): see the numbers below")
    explanation = (
        "Why: holding y constant forces nu2 = [p, q, r] = 0 and nu2_dot = 0 (Q(eta2) is "
        "invertible away from theta = +-pi/2). Every r_G term of the translational rows is "
        "multiplied by nu2 or nu2_dot: M gives -m S(r_G) nu2_dot, C nu gives "
        "-m S(nu1) nu2 - m S(S(nu2) r_G) nu2 (and C nu has no other translational term), and "
        "gravity's r_G part r_G x f_G sits in the moment rows only. So on the zero-dynamics "
        "manifold m nu1_dot + D_1 nu1 + R(eta0)^T [0, 0, m g] = [0, 0, U1] exactly, for any "
        "r_G: m u_dot = -c_x u - m g R_31, m v_dot = -c_y v - m g R_32 (R_31 = -sin theta0, "
        "R_32 = cos theta0 sin phi0), and U1 takes the w row. Physically: a body that does not "
        "rotate moves all its points alike, so where the mass sits does not matter for the "
        "translation. r_G only enters the moment rows, which fix U2..U4 (at level hover "
        "U* = [m g, m g y_G, -m g x_G, 0], docs/model.md sec. 3.3). Other equilibria: level "
        "attitude is the only equilibrium the outputs can hold with the position free; a held "
        "tilt "
        "(phi0, theta0) != 0 has no equilibrium but a relative one, a steady drift at the "
        "velocity where drag balances the tilted thrust (u*, v* in the table, about 10 m/s for "
        "0.1 rad with this drag). Its linearization is again {0, 0, -c_x/m, -c_y/m}, also "
        "independent of r_G (and of the tilt, because the body-axis u and v rows do not "
        "contain w). What does depend on r_G: the input that holds the outputs, and the "
        "internal dynamics when the outputs move (nu2 != 0: the terms m (nu2_dot x r_G + "
        "nu2 x (nu2 x r_G)) drive x, y), as the moving-output simulation shows "
        "(docs/model.md sec. 4.1).")
    slim = lambda d: {"max_spread": d["max_spread"],
                      "max_error_vs_analytic": d["max_error_vs_analytic"],
                      "duration": float(d["t"][-1]), "moving": d["moving"]}
    p = default_parameters()
    return {"finding": finding, "unchanged_with_r_G": unchanged, "explanation": explanation,
            "expected_r0": zd["expected_r0"], "c_x_over_m": p[IDX["c_x"]] / p[IDX["m"]],
            "cases": zd["cases"], "max_eig_diff_over_r_G": zd["max_eig_diff_over_r_G"],
            "sensitivity": sens, "nonlinear_held": slim(held), "nonlinear_moving": slim(mov)}


def _adaptive_summary(design, study):
    lyap = {k: {**v["summary"], "r_hat_final": v["metrics"]["r_hat_final"],
                "tail_rms_position_error": v["metrics"]["rms_position_error_tail"]}
            for k, v in study.items()}
    p, po = lyap.get("paper"), lyap.get("paper, oracle B")
    r, ro = lyap.get("output regulation"), lyap.get("output regulation, oracle B")
    parts = []
    if p:
        parts.append(
            f"In the paper's configuration V does increase after the step beyond numerical "
            f"noise: from {p['V_at_step']:.3g} at the step it first falls, then climbs by "
            f"{p['max_rise']:.3g} ({100 * p['max_rise_relative']:.3g} % of V(t_step)) to "
            f"{p['V_max_after_step']:.3g} at t = {p['t_V_max']:.3g} s, and only then decays "
            f"(to {p['V_final']:.2g} at 20 s; the estimate still converges). ")
    if po:
        parts.append(
            f"Main reason, the outer position loop: the error model treats phi_d, theta_d as "
            f"references whose second derivatives are zero and whose first derivatives are only "
            f"the reference-jerk part, but the position loop moves them with the position error, "
            f"so e_s_dot = A e_s + B Phi r_tilde does not hold and V_dot = -e^T Q e is not "
            f"guaranteed. Even with the ideal B (oracle variant) V still rises by "
            f"{100 * po['max_rise_relative']:.3g} %; in both, most of the positive dV/dt is "
            f"not explained by the continuous error model ('unexplained' "
            f"{p['unexplained_positive_integral']:.3g} and "
            f"{po['unexplained_positive_integral']:.3g}). ")
    if r and ro:
        parts.append(
            f"Without the position loop (pure output regulation of [z, phi, theta, psi], "
            f"phi_d = theta_d = 0) the error model is exact, but V still rises by "
            f"{100 * r['max_rise_relative']:.3g} % within {1000 * (r['t_max_rise'] - 1.0):.0f} ms "
            f"of the step. Second reason, the law's own approximation: the exact error model has "
            f"B_true = [0; H M(r_G)^{{-1}}], the law uses M_hat = M(r_hat) (docs/model.md "
            f"sec. 3.2, 4.2), "
            f"so "
            f"V_dot = -e^T Q e + 2 e^T P (B_true - B) Phi r_tilde, and the second term is large "
            f"right after the step (the inertia about the CoG at [6, 6, 0] cm is 0.0021 kg m^2 "
            f"in one direction against the model's 0.007; positive part integrates to "
            f"{r['mismatch_positive_integral']:.3g}). With the true B in the update (oracle, "
            f"not implementable) V is non-increasing up to discretization: the largest rise is "
            f"{100 * ro['max_rise_relative']:.2g} % of V(t_step), in {ro['n_increasing_steps']} "
            f"of {ro['n_steps']} steps, right after the step, from the 1 kHz zero-order hold and "
            f"Euler update (the controller sees e_s = 0 at the step sample, so r_hat does not "
            f"move during the first step while e_s grows). That residue is a discretization "
            f"error: it shrinks when dt shrinks, while the M_hat rise does not "
            f"(tests/test_analysis.py checks both).")
    return {"design": design, "lyapunov": lyap, "explanation": "".join(parts)}


def _fm_summary(fm, grid):
    ctls = {}
    x, y = np.meshgrid(fm["x_G"], fm["y_G"])
    radius = np.hypot(x, y)
    adm = fm["admissible"]
    for name, c in fm["controllers"].items():
        tail = c["tail_rms"][adm]
        finite = tail[np.isfinite(tail)]
        failed_r = radius[c["failed"]]
        ok_r = radius[adm & ~c["failed"]]
        first_fail = failed_r.min() if failed_r.size else np.inf
        below = ok_r[ok_r < first_fail]
        ctls[name] = {k: c[k] for k in ("label", "survive_fraction", "n_failed", "n_diverged",
                                        "rk4_stiff", "seconds")}
        ctls[name].update(median_tail_rms=float(np.median(tail)) if tail.size else np.nan,
                          max_finite_tail_rms=float(finite.max()) if finite.size else np.nan,
                          smallest_failing_radius=float(first_fail),
                          survive_radius=float(below.max()) if below.size else 0.0)
    p = default_parameters()
    return {"grid": grid, "half_width": float(fm["x_G"][-1]), "duration": fm["duration"],
            "t_step": fm["t_step"], "threshold": fm["threshold"], "n_points": fm["n_points"],
            "tail_fraction": fm.get("tail_fraction", config.get("metrics.tail_fraction")),
            "n_admissible": fm["n_admissible"],
            "admissible_radius": float(np.sqrt(min(p[IDX["Ixx"]], p[IDX["Iyy"]]) / p[IDX["m"]])),
            "controllers": ctls, "seconds": fm["seconds"],
            "adaptive_vs_projection": fm.get("adaptive_vs_projection")}


MAP_STEP_TIME = 1.0
"""When the CoG steps in the failure map's flights (s): ``quadcog analyze`` flies longer."""
ANALYSIS_FILES = ("pd_sigma.png", "zero_dynamics.png", "lyapunov.png", "failure_map.npz",
                  "failure_map.json", "failure_map.png", "analysis.md", "report_fragment.tex",
                  "analysis.json")
"""The files ``analyze`` writes, together (``quadcog.files.RunFiles``)."""


def analyze(out_dir: str | os.PathLike[str], grid: int = 41, progress: bool = True,
            duration: float = 20.0) -> dict[str, Any]:
    """Run the whole analysis and write it to ``out_dir`` (created if needed).

    Writes pd_sigma.png, zero_dynamics.png, lyapunov.png, failure_map.png, failure_map.npz,
    failure_map.json, analysis.json, analysis.md and report_fragment.tex (the PDF's analysis
    section).

    Parameters
    ----------
    out_dir : str or os.PathLike
        The folder.
    grid : int
        Failure-map points per axis (grid x grid offsets over [-arm, arm]^2 m, arm = the
        Hummingbird's 0.17 m).
    progress : bool
        Print part names and a progress bar for the failure map on stderr.
    duration : float
        Seconds per failure-map flight [s].

    Returns
    -------
    dict
        The summary (the numbers of analysis.json, as Python/numpy values; complex
        eigenvalues stay complex).
    """
    # the failure map's arguments are checked before the first part's minutes of work: the
    # CoG steps at MAP_STEP_TIME, so a flight must last longer (it never happened before)
    if validate.positive(duration, "failure_map: duration", unit="s") <= MAP_STEP_TIME:
        validate.fail("failure_map: duration", f"a number > {MAP_STEP_TIME:g} (s): the CoG "
                      f"steps at t = {MAP_STEP_TIME:g} s", duration)
    check_arguments(grid, THRESHOLD, duration, MAP_STEP_TIME, THRESHOLD,
                    ("pd", "fl", "adaptive"), None)
    out = Path(out_dir)
    # and the files: none may be a folder, a link or a FIFO (never replaced), written at the
    # end all together (quadcog.files.RunFiles), analysis.json last
    creatable_folder(out, "out_dir", InputError)
    check_outputs([(f"out_dir (its {name})", out / name) for name in ANALYSIS_FILES])
    t0 = time.perf_counter()
    timing = {}

    _say(progress, "analysis: PD design")
    t = time.perf_counter()
    pd = pd_design()
    timing["pd_design"] = time.perf_counter() - t

    _say(progress, "analysis: zero dynamics")
    t = time.perf_counter()
    zd = zero_dynamics_study()
    timing["zero_dynamics"] = time.perf_counter() - t

    _say(progress, "analysis: adaptive design and Lyapunov function")
    t = time.perf_counter()
    design = design_checks()
    study = lyapunov_study()
    timing["adaptive"] = time.perf_counter() - t

    t = time.perf_counter()
    bar = ProgressBar(f"analysis: failure map {grid}x{grid}") if progress else None
    try:
        fm = failure_map(grid=grid, duration=duration, progress=bar)
    finally:                        # an interrupt's message then starts on a line of its own
        if bar:
            bar.close()
    fm["adaptive_vs_projection"] = adaptive_failures_vs_projection(fm)
    timing["failure_map"] = time.perf_counter() - t

    summary = {
        "pd_design": _pd_summary(pd),
        "zero_dynamics": _zd_summary(zd),
        "adaptive": _adaptive_summary(design, study),
        "failure_map": _fm_summary(fm, grid),
        "figures": ["pd_sigma.png", "zero_dynamics.png", "lyapunov.png", "failure_map.png"],
        "timing": timing,
    }
    with RunFiles(out, owned=ANALYSIS_FILES) as files:  # all or none, analysis.json last
        plot_sigma(pd, files.path("pd_sigma.png"))
        plot_zero_dynamics(zd, files.path("zero_dynamics.png"))
        plot_lyapunov(study, files.path("lyapunov.png"))
        save_failure_map(fm, files.path("failure_map.npz"), files.path("failure_map.json"))
        plot_failure_map(fm, files.path("failure_map.png"))
        summary["seconds"] = time.perf_counter() - t0
        summary["machine"] = f"run {run_stamp()}"      # the timings above came from it
        write_markdown(summary, files.path("analysis.md"))
        write_latex(summary, files.path("report_fragment.tex"))
        write_json(summary, files.path("analysis.json"))
    _say(progress, f"analysis: wrote {out} in {summary['seconds']:.1f} s")
    return summary
