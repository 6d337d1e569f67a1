"""`quadcog animate`: a GIF of a run folder, frames at the asked rate, the vehicle moving."""
import numpy as np
from PIL import Image
import pytest

from quadcog.cli import main
from quadcog.viz.animation import frame_times


def test_frame_times_rate_and_cap():
    t = np.arange(0, 10.0005, 0.001)
    f = frame_times(t, fps=10, speed=1.0, max_frames=1000)
    assert np.allclose(np.diff(f[:-1]), 0.1) and f[-1] == t[-1]
    f = frame_times(t, fps=10, speed=1.0, max_frames=11)     # 10 s at 10 fps would be 101
    assert len(f) == 11 and f[0] == 0 and f[-1] == t[-1]


def test_animate_a_run_folder(tmp_path, capsys):
    run = tmp_path / "run"
    assert main(["run", "fig6", "--set", "duration=1.6", "--quiet", "--no-plot",
                 "--out", str(run)]) == 0
    assert main(["animate", str(run), "--fps", "5", "--max-frames", "6"]) == 0
    gif = Image.open(run / "flight.gif")
    assert gif.n_frames == 6
    assert gif.info["duration"] == pytest.approx(200, abs=1)     # 5 frames per second
    frames = []
    for k in (0, gif.n_frames - 1):
        gif.seek(k)
        frames.append(np.asarray(gif.convert("L"), dtype=float))
    assert np.abs(frames[0] - frames[1]).mean() > 0.1       # time text and vehicle changed


def test_animate_names_a_missing_folder(tmp_path, capsys):
    assert main(["animate", str(tmp_path / "nope")]) == 2
    err = capsys.readouterr().err
    assert "nope" in err and "quadcog run" in err
