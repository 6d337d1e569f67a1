"""The flight figure: panels present only when they say something, legends off the data,
disturbances shaded, one title scheme."""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from quadcog import AdaptiveFeedbackLinearization, CascadePD, CogProfile, Disturbance, simulate
from quadcog.viz.plots import flight_title, plot_flight

PULSE = [Disturbance(t=0.3, duration=0.1, force=(0.5, 0, 0))]


@pytest.fixture(scope="module")
def figures():
    """The figures of a still flight and of one with a CoG step and a pushed pulse (drawn
    once for the tests below)."""
    still = simulate(CascadePD(), "hover", duration=0.5)
    moving = simulate(AdaptiveFeedbackLinearization(), "hover", duration=0.6,
                      cog=CogProfile([(0.2, (0.02, 0.0, 0.0), 0.0)]), disturbances=PULSE)
    figs = plot_flight(still), plot_flight(moving, disturbances=PULSE)
    yield figs
    for fig in figs:
        plt.close(fig)


def _ylabels(fig):
    return [a.get_ylabel() for a in fig.axes]


def test_cog_panel_only_when_the_cog_moves(figures):
    f1, f2 = figures
    assert not any("CoG" in y for y in _ylabels(f1))
    assert any("CoG" in y for y in _ylabels(f2))
    for fig in (f1, f2):
        labels = _ylabels(fig)
        assert "position error (cm)" in labels
        for y in labels:            # a unit on every axis
            assert "(" in y and ")" in y, y


def test_legends_never_overlap_the_data_area(figures):
    fig = figures[1]
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    for a in fig.axes:
        leg = a.get_legend()
        assert leg is not None
        box, area = leg.get_window_extent(renderer), a.get_window_extent(renderer)
        assert box.y0 >= area.y1 - 1, f"legend of {a.get_ylabel()!r} covers its panel"


def test_disturbance_pulses_are_shaded_where_they_act(figures):
    for a in figures[1].axes:
        xs = [(p.get_x(), p.get_x() + p.get_width()) for p in a.patches]
        assert any(np.allclose(x, (0.3, 0.4)) for x in xs), a.get_ylabel()


def test_one_title_scheme():
    assert flight_title("adaptive_feedback_linearization", "fig6") == "fig6: adaptive FL"
    assert flight_title("cascade_pd") == "cascade PD"
    assert flight_title("my_law", "x") == "x: my law"
