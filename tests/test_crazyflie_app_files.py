"""The Crazyflie app writer (``write_crazyflie_app``, ``quadcog export --target crazyflie``)
never writes through what is not a regular file, and leaves the old app or the complete new
one: it wrote through a symbolic link (replacing the link's target), blocked for ever on a
FIFO named like one of the app's files, and a failure half-way left new files beside old."""
import os
from pathlib import Path
import subprocess
import sys

import pytest

from quadcog.embedded.crazyflie_app import write_crazyflie_app
from quadcog.errors import ExportError

ROOT = Path(__file__).resolve().parent.parent


def _snapshot(folder):
    return {p.relative_to(folder).as_posix(): (p.read_bytes() if p.is_file() else None)
            for p in sorted(folder.rglob("*"))}


def test_a_link_in_the_app_is_refused_and_its_target_kept(tmp_path):
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    app = tmp_path / "app"
    write_crazyflie_app("composite", app)
    (app / "Makefile").unlink()
    (app / "Makefile").symlink_to(victim)
    before = _snapshot(app)
    with pytest.raises(ExportError, match=r"Makefile: is a symbolic link"):
        write_crazyflie_app("composite", app)
    assert victim.read_text() == "precious\n"
    assert _snapshot(app) == before


@pytest.mark.parametrize("rel", ["Kbuild", "src/quadcog_composite.c"])
def test_a_fifo_in_the_app_is_refused_without_blocking(tmp_path, rel):
    app = tmp_path / "app"
    (app / "src").mkdir(parents=True)
    os.mkfifo(app / rel)
    code = ("from quadcog.embedded.crazyflie_app import write_crazyflie_app\n"
            f"write_crazyflie_app('composite', {str(app)!r})\n")
    res = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                         timeout=120)       # the old writer opened the FIFO and waited for ever
    assert res.returncode != 0
    assert "ExportError" in res.stderr and "FIFO" in res.stderr, res.stderr[-500:]
    assert sorted(p.name for p in app.rglob("*") if p.is_file()) == []


def test_a_failure_half_way_leaves_the_old_app(tmp_path, monkeypatch):
    app = tmp_path / "app"
    write_crazyflie_app("composite", app, command="the first export")
    before = _snapshot(app)
    calls = []
    write_text = Path.write_text

    def failing(self, text, *args, **kwargs):
        calls.append(self)
        if len(calls) == 4:             # the first file of src/, after the three at the top
            raise OSError(28, "No space left on device", str(self))
        return write_text(self, text, *args, **kwargs)

    monkeypatch.setattr(Path, "write_text", failing)
    with pytest.raises(ExportError, match="No space left on device"):
        write_crazyflie_app("composite", app, command="the second export")
    monkeypatch.undo()
    assert len(calls) == 4
    assert _snapshot(app) == before            # no new file beside an old one, no temporary


def test_an_empty_folder_name_is_refused(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ExportError, match=r"^out: expected a folder path"):
        write_crazyflie_app("composite", "")
    assert list(tmp_path.iterdir()) == []
