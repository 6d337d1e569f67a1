"""Guards of a run's timeline (quadcog.sim.timeline, schedule, divergence) against oracles
written here: a CoG change acts from its own time (the docstring's "from time t"), a force
pulse of duration D gives a free body the momentum F D (Newton, RK4 exact for a constant
force), the tail metric is the RMS of the errors of the last quarter computed from the
flown states, and the divergence rule reads |phi| and |theta|, not the heading. Times out
of order take the timeline's second path (CoG and wrench), held to an oracle too.
(bench/mutations.py: cog_change_one_step_late, disturbance_one_step_long,
tail_start_is_the_fraction, divergence_tilt_reads_yaw.)"""
import math

import numpy as np
import pytest

import quadcog
from quadcog import HUMMINGBIRD, CascadePD, CogProfile, Disturbance, simulate
from quadcog.sim.divergence import DivergenceCause, Limits, first_divergence
from quadcog.sim.timeline import CogChange, wrench_table


def test_a_cog_change_acts_from_its_own_time():
    """r_G(t) is the new CoG at t = t_change itself (a step has no ramp), the old one just
    before; the same at a sample of a flight's grid (t_k = k dt lands on 0.25 s exactly)."""
    r = (0.02, -0.01, 0.005)
    for t_c in (0.25, 0.3, 1.0 / 3.0, 7.1):
        got = CogProfile([CogChange(t_c, r)]).sample([np.nextafter(t_c, 0.0), t_c, t_c + 1e-9])
        assert got[0].tolist() == [0.0, 0.0, 0.0], t_c
        assert got[1].tolist() == list(r), f"change at {t_c} s not in force at its own time"
        assert got[2].tolist() == list(r)
    res = simulate(CascadePD(), "hover", duration=0.5, cog=CogProfile.step(0.25, r))
    k = int(np.flatnonzero(res.t == 0.25)[0])
    assert k == 250
    assert res.r_G[k - 1].tolist() == [0.0, 0.0, 0.0]
    assert res.r_G[k].tolist() == list(r)


def test_a_force_pulse_gives_the_momentum_force_times_duration():
    """A body without drag held at hover thrust (U1 = m g, no moments, CoG at O) and pushed
    along x by F for D seconds: its speed afterwards is F D / m (Newton's second law; the
    pulse is [t, t + D), 500 steps of 1 ms, and RK4 integrates a constant force exactly)."""
    v = HUMMINGBIRD.replace(c_x=0.0, c_y=0.0, c_z=0.0, c_phi=0.0, c_theta=0.0, c_psi=0.0)
    F, D = 0.4, 0.5
    hold = lambda t, x, ref, c: np.array([v.m * v.g, 0.0, 0.0, 0.0])
    res = simulate(hold, "hover", duration=1.0, vehicle=v, path="python",
                   disturbances=[Disturbance(t=0.25, duration=D, force=(F, 0.0, 0.0))])
    assert res.x[-1, 6] == pytest.approx(F * D / v.m, rel=1e-9)
    assert np.abs(res.x[:, 3:6]).max() < 1e-12          # a force at O turns nothing
    # the table itself: the pulse covers D / dt samples of a grid that hits both its ends
    t = np.arange(1025) / 1024.0
    w = wrench_table([Disturbance(t=0.25, duration=0.5, force=(F, 0.0, 0.0))], t)
    assert np.count_nonzero(w[:, 0]) == 512
    assert w[:, 0].sum() / 1024.0 == pytest.approx(F * 0.5, rel=1e-15)


def test_the_tail_metric_is_the_last_quarter_of_the_flown_errors():
    """The compiled flight's tail RMS against the errors it flew: sqrt(mean(e^2)) over the
    samples with t >= (1 - 0.25) T (quadcog.config's tail_fraction), computed here."""
    T = 2.0
    res = simulate(CascadePD(), "circle", duration=T, cog=CogProfile.step(0.1, (0.03, 0.0, 0.0)))
    assert quadcog.config.defaults["metrics.tail_fraction"] == 0.25
    e = np.linalg.norm(res.x[:, :3] - res.ref[:, :3], axis=1)
    tail = res.t >= 0.75 * T - 1e-9
    assert tail.sum() == 501
    expected = math.sqrt(np.mean(e[tail] ** 2))
    everything = math.sqrt(np.mean(e ** 2))
    assert abs(expected - everything) > 1e-3 * expected     # the window matters here
    assert res.metrics.rms_position_error_tail == pytest.approx(expected, rel=1e-9)
    assert res.metrics.rms_position_error == pytest.approx(everything, rel=1e-9)


def test_the_divergence_rule_reads_roll_and_pitch_not_yaw():
    """|phi| or |theta| over the tilt limit diverges (85 deg by default); a heading of any
    size does not."""
    limits = Limits()
    x = np.zeros((4, 12))
    x[0, 5] = 3.0                      # yaw 172 deg, level: flying
    x[1, 5] = -3.1
    x[2, 4] = -1.55                    # pitch 89 deg
    x[3, 3] = 1.55                     # roll 89 deg
    assert first_divergence(x[:2], np.zeros(2), limits) == (None, None)
    assert first_divergence(x[1:3], np.zeros(2), limits) == (1, DivergenceCause.TILT)
    assert first_divergence(x[3:], np.zeros(1), limits) == (0, DivergenceCause.TILT)
    pitch = np.zeros((2, 12))
    pitch[1, 4] = math.radians(86.0)
    assert first_divergence(pitch, np.zeros(2), limits) == (1, DivergenceCause.TILT)


def _cog_oracle(changes, times):
    """r_G at each time, written from the docstrings: the last change started at or before
    t holds, moving from the previous change's r to its own over its ramp."""
    out = np.zeros((len(times), 3))
    for k, t in enumerate(times):
        prev, value = np.zeros(3), np.zeros(3)
        for c in changes:
            if c.t <= t:
                s = 1.0 if c.ramp == 0 else min(max((t - c.t) / c.ramp, 0.0), 1.0)
                value = prev + s * (np.array(c.r) - prev)
            prev = np.array(c.r)
        out[k] = value
    return out


def test_times_out_of_order_give_each_time_its_own_cog_and_wrench():
    """The timeline's second path, for times not in order (a run's grid takes the first):
    each shuffled time gets the CoG and the wrench the oracle written here gives it, and the
    same bits as the same times sorted."""
    changes = [CogChange(0.2, (0.01, 0.0, 0.0), 0.15), CogChange(0.4, (0.0, 0.02, -0.01)),
               CogChange(1.0, (-0.03, 0.0, 0.0), 0.5)]
    pulses = [Disturbance(t=0.1, duration=0.3, force=(1.0, 0.0, 0.0)),
              Disturbance(t=0.2, duration=0.5, moment=(0.0, 0.0, 0.1)),
              Disturbance(t=0.25, duration=0.05, force=(0.0, 2.0, 0.0))]
    rng = np.random.default_rng(7)
    t = np.concatenate([rng.uniform(0.0, 2.0, 300),
                        [0.0, 0.1, 0.2, 0.25, 0.3, 0.4, 0.5, 0.7, 1.0, 1.5, 2.0]])
    shuffled = rng.permutation(t)
    assert not (np.diff(shuffled) >= 0).all()
    profile = CogProfile(changes)
    got = profile.sample(shuffled)
    np.testing.assert_allclose(got, _cog_oracle(changes, shuffled), rtol=0, atol=1e-15)
    order = np.argsort(shuffled, kind="stable")
    assert got[order].tolist() == profile.sample(shuffled[order]).tolist()
    w = wrench_table(pulses, shuffled)
    expected = np.zeros((t.size, 6))
    for k, tk in enumerate(shuffled):
        for d in pulses:
            if d.t <= tk < d.t + d.duration:
                expected[k] += np.concatenate([d.force, d.moment])
    np.testing.assert_allclose(w, expected, rtol=0, atol=1e-15)
    assert w[order].tolist() == wrench_table(pulses, shuffled[order]).tolist()
