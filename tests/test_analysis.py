"""quadcog.studies.analysis: PD design, zero dynamics, adaptive design and Lyapunov function,
failure map. Each test checks a number that could come out otherwise."""
from conftest import assert_close
import numpy as np
import pytest

import quadcog
from quadcog.model.conventions import IDX
from quadcog.studies.analysis.adaptive_design import design_checks, lyapunov_study
from quadcog.studies.analysis.analysis_files import jsonable
from quadcog.studies.analysis.failure_map import failure_map, plot_failure_map, save_failure_map
from quadcog.studies.analysis.frequency import channel_loop, channel_margins, gain_range_by_eigenvalues
from quadcog.studies.analysis.linear import hover_statespace
from quadcog.studies.analysis.pd_design import pd_design
from quadcog.studies.analysis.zero_dynamics import nonlinear_check, rg_sensitivity, zero_dynamics_eigenvalues


@pytest.fixture(scope="module")
def pd():
    return pd_design()


# -- 1. PD design -----------------------------------------------------------------------------

def test_pd_closed_loop_eigenvalues_negative(pd):
    eig = pd["eigenvalues"]
    assert eig.shape == (12,)
    assert np.all(eig.real < 0)
    chosen = np.sort(np.concatenate([np.asarray(v, float) for v in pd["poles"].values()]))
    assert np.allclose(np.sort(eig.real), chosen, atol=1e-8)


def test_pd_margins_finite_positive_and_match_eigenvalues(pd):
    ctl = quadcog.CascadePD()
    for i, m in enumerate(pd["margins"]):
        assert np.isfinite(m["phase_margin_deg"]) and 30 < m["phase_margin_deg"] < 180
        assert m["gain_crossover_rad_s"] > 0
        assert m["gain_margin_db"] > 0          # inf: no phase crossover above
        assert m["lower_gain_margin_db"] < 0    # -inf: the gain may go to zero
        # the margins are where a scalar gain on this channel makes A - B K unstable
        k_lo, k_hi = gain_range_by_eigenvalues(ctl.A, ctl.B, ctl.K, i)
        if np.isfinite(m["lower_gain_margin_db"]):
            assert 20 * np.log10(k_lo) == pytest.approx(m["lower_gain_margin_db"], abs=1e-6)
        else:
            assert k_lo == 0.0
        assert np.isinf(k_hi) == np.isinf(m["gain_margin_db"])
    # the x-theta and y-phi cascades are conditionally stable: a finite lower margin
    assert np.isfinite(pd["margins"][2]["lower_gain_margin_db"])
    assert pd["min_sigma_return_difference"] > 0.5


def test_sigma_agrees_with_direct_numpy(pd):
    ctl = quadcog.CascadePD()
    k = 437
    w = pd["omega"][k]
    L = ctl.K @ np.linalg.inv(1j * w * np.eye(12) - ctl.A) @ ctl.B
    s = np.linalg.svd(L, compute_uv=False)
    assert np.allclose(pd["sigma_L"][k], s, rtol=1e-10)
    s_rd = np.linalg.svd(np.eye(4) + L, compute_uv=False)
    assert pd["sigma_min_return_difference"][k] == pytest.approx(s_rd[-1], rel=1e-10)
    # |L_i| = 1 at each reported gain crossover, and the phase margin is read there
    for i, m in enumerate(pd["margins"]):
        A_i, b_i, k_i = channel_loop(ctl.A, ctl.B, ctl.K, i)
        wc = m["gain_crossover_rad_s"]
        Li = k_i @ np.linalg.solve(1j * wc * np.eye(12) - A_i, b_i)
        assert abs(Li) == pytest.approx(1.0, abs=1e-9)
        assert 180 + np.degrees(np.angle(Li)) == pytest.approx(m["phase_margin_deg"], abs=1e-6)


def test_margin_finder_on_a_textbook_loop():
    # L(s) = 2 / (s (s + 1) (s + 2)): phase crossover at sqrt(2) rad/s with |L| = 1/3,
    # so the gain margin is 20 log10(3) = 9.54 dB; the gain range from eigenvalues is (0, 3).
    A = np.array([[0.0, 1, 0], [0, 0, 1], [0, -2, -3]])
    b, k = np.array([0.0, 0, 1]), np.array([2.0, 0, 0])
    m = channel_margins(A, b, k)
    assert m["phase_crossover_rad_s"] == pytest.approx(np.sqrt(2), rel=1e-9)
    assert m["gain_margin_db"] == pytest.approx(20 * np.log10(3), abs=1e-8)
    wc = m["gain_crossover_rad_s"]
    Lc = 2 / (1j * wc * (1j * wc + 1) * (1j * wc + 2))
    assert abs(Lc) == pytest.approx(1, abs=1e-10)
    assert m["phase_margin_deg"] == pytest.approx(180 + np.degrees(np.angle(Lc)), abs=1e-8)
    k_lo, k_hi = gain_range_by_eigenvalues(A, b[:, None], k[None, :], 0)
    assert k_hi == pytest.approx(3.0, rel=1e-9) and k_lo == 0.0


def test_hover_statespace_is_the_numerical_jacobian():
    """A and B of the control.StateSpace against central differences of the generated
    dynamics at the hover trim, with the CoG off centre (so the trim holds a moment)."""
    model = quadcog.load()
    v = quadcog.HUMMINGBIRD.with_cog((0.02, -0.01, 0.0))
    sys = hover_statespace(v, outputs=("x", "y", "z", "psi"))
    p = v.parameters()
    x0 = np.zeros(12)
    x0[2] = 1.0
    U0 = quadcog.hover_trim(p)
    assert np.abs(model.dynamics(x0, U0, p)).max() < 1e-12       # it is an equilibrium
    h = 1e-6
    A = np.column_stack([(model.dynamics(x0 + h * e, U0, p) - model.dynamics(x0 - h * e, U0, p))
                         / (2 * h) for e in np.eye(12)])
    B = np.column_stack([(model.dynamics(x0, U0 + h * e, p) - model.dynamics(x0, U0 - h * e, p))
                         / (2 * h) for e in np.eye(4)])
    assert np.allclose(sys.A, A, atol=1e-7) and np.allclose(sys.B, B, atol=1e-7)
    assert sys.output_labels == ["x", "y", "z", "psi"] and sys.input_labels == ["U1", "U2",
                                                                                  "U3", "U4"]
    assert np.array_equal(sys.C[3], np.eye(12)[5]) and not np.any(sys.D)
    with pytest.raises(quadcog.InputError, match="'nope'"):
        hover_statespace(outputs=("x", "nope"))


# -- 2. zero dynamics ---------------------------------------------------------------------------

def test_zero_dynamics_at_r0_are_paper_eq7():
    p = quadcog.default_parameters(c_x=0.1, c_y=0.25)       # distinct c_x, c_y
    zd = zero_dynamics_eigenvalues(p)
    m = p[IDX["m"]]
    expected = np.sort([0.0, 0.0, -p[IDX["c_x"]] / m, -p[IDX["c_y"]] / m])
    assert np.allclose(np.sort(zd["eigenvalues"].real), expected, atol=1e-12)
    assert np.allclose(zd["eigenvalues"].imag, 0, atol=1e-12)
    assert zd["residual"] < 1e-10
    assert np.allclose(zd["U_hold"], [m * p[IDX["g"]], 0, 0, 0], atol=1e-12)


@pytest.mark.parametrize("y0", [(1.0, 0.0, 0.0, 0.0), (2.0, 0.15, -0.1, 0.7)])
def test_zero_dynamics_do_not_change_with_r_G(y0):
    """The finding: eigenvalues (and the whole zero-dynamics vector field) are independent of
    r_G; only the input that holds the outputs changes. Fails if r_G entered the zero dynamics."""
    base = quadcog.default_parameters(c_x=0.1, c_y=0.25)
    ref = zero_dynamics_eigenvalues(base, y0)
    for r in [(0.03, 0.02, 0.01), (0.06, 0.06, 0.0), (-0.05, 0.03, 0.02), (0.0, 0.0, 0.05)]:
        zd = zero_dynamics_eigenvalues(quadcog.with_cog(base, r), y0)
        assert np.allclose(zd["eigenvalues"], ref["eigenvalues"], atol=1e-10)
        assert np.allclose(zd["zeta_eq"], ref["zeta_eq"], atol=1e-10)
        assert np.max(np.abs(zd["dzeta_dot_dr"])) < 1e-10
        # ... while the holding moments do change (docs/model.md sec. 3.3 at level; a pure z_G
        # offset needs no moment at level, and one of m g z_G sin(tilt) tilted)
        if r[0] or r[1]:
            assert np.max(np.abs(zd["U_hold"][1:3] - ref["U_hold"][1:3])) > 0.05
    if y0[1:3] == (0.0, 0.0):
        m, g = base[IDX["m"]], base[IDX["g"]]
        zd = zero_dynamics_eigenvalues(quadcog.with_cog(base, (0.03, 0.02, 0.0)), y0)
        assert np.allclose(zd["U_hold"], [m * g, m * g * 0.02, -m * g * 0.03, 0], atol=1e-12)


def test_zero_dynamics_r_G_sensitivity_over_the_manifold():
    s = rg_sensitivity(n_points=40, seed=3)
    assert s["max_residual"] < 1e-10                 # the manifold is invariant
    assert s["max_dzeta_dot_dr"] < 1e-9              # r_G does not enter the zero dynamics
    assert s["max_dU_dr"] > 1.0                      # but it does enter the input


def test_zero_dynamics_nonlinear_held_vs_moving():
    offsets = [(0.0, 0.0, 0.0), (0.06, 0.06, 0.0), (-0.05, 0.03, 0.02)]
    held = nonlinear_check(offsets, duration=1.5)
    assert held["max_spread"] < 1e-7
    assert held["max_error_vs_analytic"] < 1e-7      # u0 exp(-c t / m), x = u0 m / c (1 - ...)
    moving = nonlinear_check(offsets, duration=1.5, moving=True)
    assert moving["max_spread"] > 1e-3               # internal dynamics do see r_G


# -- 3. adaptive design ---------------------------------------------------------------------------

def test_adaptive_error_model_and_its_lyapunov_matrix():
    """The error model A of the adaptive law (e_s = [e, e_dot], e_ddot = -kp e - kd e_dot
    for z, phi, theta, psi) has the poles it was given, and P is the Lyapunov matrix of that
    model for Q by its definition, not by the equation the design solves: along the flow
    e(t) = exp(A t) e0, V(e0) = e0^T P e0 = int_0^inf e^T Q e dt, i.e.
    P = int_0^inf exp(A^T t) Q exp(A t) dt (Simpson's rule on the exact flow). A Q with
    distinct entries makes a transposed A or a mis-ordered Q in the design show;
    design_checks reports the same eigenvalues and P."""
    from scipy.linalg import expm
    poles = dict(poles_z=(-2.0, -5.0), poles_attitude=(-8.0, -13.0), poles_psi=(-3.0, -4.5))
    Q = np.diag([4.0, 3.0, 2.0, 1.5, 1.0, 0.5, 0.3, 0.2])
    ctl = quadcog.AdaptiveFeedbackLinearization(Q=Q, **poles)
    chosen = np.sort(np.r_[poles["poles_z"], poles["poles_attitude"], poles["poles_attitude"],
                           poles["poles_psi"]])
    assert np.allclose(np.sort(np.linalg.eigvals(ctl.A_error).real), chosen, atol=1e-9)
    h, n = 1e-3, 12000                    # 12 s: exp(-2 * 2 * 12) of V left at the slowest pole
    step, flow = expm(ctl.A_error * h), np.eye(8)
    P = np.zeros((8, 8))
    for k in range(n + 1):
        weight = 1 if k in (0, n) else (4 if k % 2 else 2)
        P += weight * flow.T @ Q @ flow
        flow = step @ flow
    P *= h / 3
    assert_close(ctl.P, P, 1e-7, "P against int exp(A^T t) Q exp(A t) dt")
    d = design_checks(ctl)
    assert np.allclose(np.sort(d["eig_A"].real), chosen, atol=1e-9) and d["max_real_eig_A"] < 0
    assert np.allclose(d["eig_P"], np.linalg.eigvalsh(P), rtol=1e-8) and d["eig_P"][0] > 0


@pytest.fixture(scope="module")
def lyapunov_runs():
    which = ["output regulation", "output regulation, oracle B"]
    return {dt: lyapunov_study(duration=2.0, dt=dt, which=which) for dt in (1e-3, 5e-4)}


def test_lyapunov_non_increasing_in_the_exact_variant(lyapunov_runs):
    """Output regulation (exact error model) with the true B in the update: in continuous time
    V_dot = -e_s^T Q e_s <= 0. The sampled run adds a discretization error: the law sees
    e_s = 0 at the step sample and holds r_hat and U for a step of dt while e_s grows, so V can
    rise by O(dt) (here 0.6 % of V(t_step) at dt = 1 ms). Tolerance 1 % at 1 ms, and the rise
    must shrink by at least 1.6x when dt halves (first-order convergence gives 2x), which is what
    distinguishes a discretization residue from a real increase."""
    a = lyapunov_runs[1e-3]["output regulation, oracle B"]["summary"]
    b = lyapunov_runs[5e-4]["output regulation, oracle B"]["summary"]
    assert a["V_at_step"] == pytest.approx(2 * 0.06 ** 2 / 0.01)
    assert a["max_rise_relative"] < 0.01
    assert b["max_rise"] < a["max_rise"] / 1.6
    assert a["t_max_rise"] < 1.02                  # only right after the step
    assert a["V_final"] < 0.5 * a["V_at_step"]


def test_lyapunov_rises_with_M_hat_in_the_law(lyapunov_runs):
    """With the implementable law (B from M_hat) V rises by several % after the step even
    without the position loop, and halving dt does not remove it: not numerical noise."""
    a = lyapunov_runs[1e-3]["output regulation"]["summary"]
    b = lyapunov_runs[5e-4]["output regulation"]["summary"]
    assert a["max_rise_relative"] > 0.03
    assert b["max_rise_relative"] > 0.8 * a["max_rise_relative"]
    assert a["mismatch_positive_integral"] > 0.1


# -- 4. failure map ----------------------------------------------------------------------------

@pytest.mark.slow
def test_failure_map_small_grid(tmp_path):
    # x_G, y_G in {-12, -6, 0, 6, 12} cm: |r_G| >= 12 cm is inadmissible for this vehicle
    fm = failure_map(grid=5, half_width=0.12, duration=10.0)
    xs, adm = fm["x_G"], fm["admissible"]
    assert np.allclose(xs, [-0.12, -0.06, 0.0, 0.06, 0.12])
    radius = np.hypot(*np.meshgrid(xs, xs))
    assert np.array_equal(adm, radius < 0.1)
    assert fm["n_admissible"] == 9
    for name, c in fm["controllers"].items():
        assert np.all(np.isnan(c["tail_rms"][~adm])), name          # not simulated
        assert not np.any(c["failed"][~adm])
        assert np.all(np.isfinite(c["tail_rms"][adm]) | c["diverged"][adm])
    i0, i6 = 2, 3                                   # y_G = 0, x_G = 6 cm (indexed [i_y, i_x])
    ctl = fm["controllers"]
    assert ctl["pd"]["failed"][i0, i6] and ctl["fl"]["failed"][i0, i6]
    assert not ctl["adaptive"]["failed"][i0, i6]
    assert ctl["adaptive"]["tail_rms"][i0, i6] < 0.5 < ctl["pd"]["tail_rms"][i0, i6]
    assert ctl["adaptive"]["survive_fraction"] > ctl["pd"]["survive_fraction"]
    save_failure_map(fm, tmp_path / "f.npz", tmp_path / "f.json")
    plot_failure_map(fm, tmp_path / "f.png")
    data = np.load(tmp_path / "f.npz")
    assert np.array_equal(data["admissible"], adm)
    assert (tmp_path / "f.png").stat().st_size > 10000


def test_jsonable_handles_inf_nan_complex():
    assert jsonable({"a": np.array([1.0, np.inf]), "b": complex(1, -2), "c": np.nan}) == \
        {"a": [1.0, "inf"], "b": [1.0, -2.0], "c": "nan"}


def test_latex_text_escapes_every_special_character():
    from quadcog.studies.analysis.analysis_files import _tex
    out = _tex(r"V_dot = -e^T Q e, 10 % & #1 {a} ~b $c <d> \e")
    plain = out.replace(r"\_", "").replace(r"\^{}", "").replace(r"\%", "").replace(r"\&", "")
    plain = plain.replace(r"\#", "").replace(r"\{", "").replace(r"\}", "").replace(r"\$", "")
    plain = plain.replace(r"\textasciitilde{}", "").replace("$<$", "").replace("$>$", "")
    assert not set(plain) & set("_^%&#{}~$<>\\"), out


def test_report_copies_only_fragments_and_figures(tmp_path):
    """`make report` must not copy the runs' trajectories a second time."""
    from report.pdf import COPY_MARKER, _copy_results
    src = tmp_path / "paper"
    (src / "fig6").mkdir(parents=True)
    (src / "report_fragment.tex").write_text("x")
    (src / "fig6" / "flight.png").write_bytes(b"png")
    (src / "fig6" / "trajectory.csv").write_text("t_s\n0\n")
    assert _copy_results(src, tmp_path / "build" / "paper")
    got = sorted(p.relative_to(tmp_path / "build").as_posix()
                 for p in (tmp_path / "build").rglob("*") if p.is_file())
    assert got == [f"paper/{COPY_MARKER}", "paper/fig6/flight.png", "paper/report_fragment.tex"]
    assert not _copy_results(tmp_path / "nothing", tmp_path / "build" / "analysis")
