"""PX4 in the loop, faults, without PX4: no tree, a tree that does not build (the compiler's
first error line), ports taken, and the lockstep loop against a fake PX4 (a small Python
program that speaks the simulator link) that never connects, exits before connecting, stops
answering, or dies mid-flight. Every fake is gone afterwards."""
import os
from pathlib import Path
import socket
import stat
import sys
import textwrap

import numpy as np
import pytest

from quadcog.errors import Px4Error, Px4TimeoutError
from quadcog.px4 import tree
from quadcog.px4.airframe import RotorMap
from quadcog.px4.lockstep import run_lockstep
from quadcog.px4.mission import Mission, MissionLink, Waypoint
from quadcog.px4.process import MAX_INSTANCES, SIM_PORT, Px4Process, free_instance
from quadcog.px4.sensors import Sensors
from quadcog.sim.plant import Actuation, TruthOptions
from quadcog.sim.schedule import Schedule
from quadcog.trajectories.analytic import Hover
from quadcog.vehicles.vehicle import X500

ROOT = Path(__file__).resolve().parents[1]


def test_no_tree_anywhere(monkeypatch):
    monkeypatch.delenv(tree.TREE_ENV, raising=False)
    monkeypatch.setattr(tree, "shared_tarball", lambda: None)
    with pytest.raises(Px4Error, match=r"no PX4 tree.*--px4 PATH.*QUADCOG_PX4"):
        tree.find_source()


def test_named_tree_missing_or_not_px4(tmp_path, monkeypatch):
    with pytest.raises(Px4Error, match=r"argument --px4 = .*nowhere.*no such folder"):
        tree.find_source(tmp_path / "nowhere")
    monkeypatch.setenv(tree.TREE_ENV, str(tmp_path))
    with pytest.raises(Px4Error, match=r"\$QUADCOG_PX4 = .*not a PX4-Autopilot source folder"):
        tree.find_source()


def test_tree_key_follows_content_not_build(tmp_path):
    (tmp_path / "a.c").write_text("int a;\n")
    key = tree.tree_key(tmp_path)
    (tmp_path / "build").mkdir()
    (tmp_path / "build" / "x.o").write_text("object")
    assert tree.tree_key(tmp_path) == key            # the build folder is not the tree
    (tmp_path / "a.c").write_text("int b;\n")
    assert tree.tree_key(tmp_path) != key


def test_a_tree_that_does_not_build_reports_the_compilers_first_error(tmp_path, monkeypatch):
    src = tmp_path / "px4"
    (src / "ROMFS").mkdir(parents=True)
    (src / "broken.c").write_text("int ok;\noops here;\nalso bad;\n")
    (src / "Makefile").write_text(f"px4_sitl_default:\n\t{os.environ.get('CC', 'cc')} -c "
                                  f"broken.c -o broken.o\n")
    monkeypatch.setenv("QUADCOG_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(tree, "_missing_modules", lambda: [])
    with pytest.raises(Px4Error, match=r"failed .*broken\.c:2:1: error: .*full log: "):
        tree.build(src, quiet=True)
    assert not (src / ".git").exists() and not (src / "build").exists()   # user's tree intact
    copied = tmp_path / "cache" / "px4" / tree.tree_key(src) / "PX4-Autopilot"
    assert (copied / ".git").is_dir()                 # the copy became a git repository


def test_missing_build_packages_give_the_pip_line(tmp_path, monkeypatch):
    src = tmp_path / "px4"
    (src / "ROMFS").mkdir(parents=True)
    (src / "Makefile").write_text("px4_sitl_default:\n\ttrue\n")
    monkeypatch.setenv("QUADCOG_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(tree, "_missing_modules", lambda: ["empy>=3.3,<4", "pyros-genmsg"])
    from quadcog.errors import MissingDependencyError
    with pytest.raises(MissingDependencyError, match=r"pip install 'empy>=3.3,<4' pyros-genmsg"):
        tree.build(src, quiet=True)


def test_taken_simulator_port_moves_to_the_next_instance():
    first = MAX_INSTANCES - 2
    blocker = socket.socket()
    try:
        blocker.bind(("127.0.0.1", SIM_PORT + first))
    except OSError:
        pytest.skip(f"port {SIM_PORT + first} is in use already")
    blocker.listen(1)
    try:
        i, server = free_instance(first)
        server.close()
        assert i == first + 1
        with pytest.raises(Px4Error, match=f"no free PX4 instance.*TCP {SIM_PORT + first + 1}"):
            s2 = socket.socket()
            s2.bind(("127.0.0.1", SIM_PORT + first + 1))
            s2.listen(1)
            try:
                free_instance(first)
            finally:
                s2.close()
    finally:
        blocker.close()


FAKE = textwrap.dedent('''\
    #!{python}
    # a fake PX4: connects to the simulator port and answers HIL_SENSOR with
    # HIL_ACTUATOR_CONTROLS; MODE: "answer N then exit", "answer N then hang", "hang", "exit"
    import socket, struct, sys, time
    sys.path.insert(0, {root!r})
    from quadcog.px4.mavlink import MESSAGES, FrameReader, frame
    mode, n = {mode!r}, {n}
    instance = int(sys.argv[sys.argv.index("-i") + 1])
    if mode == "exit":
        sys.exit(4)
    if mode == "hang":
        time.sleep(60)
    s = socket.create_connection(("127.0.0.1", 4560 + instance))
    reader, k, seq = FrameReader({{107}}), 0, 0
    while True:
        data = s.recv(65536)
        if not data:
            break
        for msgid, _, _, payload, _ in reader.feed(data):
            t_us = struct.unpack("<Q", payload[:8])[0]
            k += 1
            if k > n:
                if mode.endswith("exit"):
                    sys.exit(3)
                time.sleep(60)
            body = struct.pack("<2Q16fB", t_us, 1, *([0.0] * 16), 0)
            s.sendall(frame(MESSAGES["HIL_ACTUATOR_CONTROLS"], body, seq))
            seq += 1
''')


def _fake(tmp_path, mode, n=0):
    path = tmp_path / "px4"
    path.write_text(FAKE.format(python=sys.executable, root=str(ROOT), mode=mode, n=n))
    path.chmod(path.stat().st_mode | stat.S_IEXEC)
    return path


def _fly(tmp_path, mode, n=0, connect_timeout=20.0, answer_timeout=20.0):
    pytest.importorskip("pymavlink")
    P = X500.parameters()
    actuation = Actuation.of(X500, TruthOptions(motor_lag=True, rotor_saturation=True))
    schedule = Schedule.build(Hover(), 5.0, 0.001)
    rotors = RotorMap((150.0,) * 4, (1000.0,) * 4, X500.thrust_constant)
    sensors = Sensors(np.array([0.2, 0.0, 0.4]), 9.81, 250.0)
    instance, server = free_instance()
    link = MissionLink(Mission((Waypoint((0.0, 0.0, 2.0), 1.0),)), instance)
    link.open()
    proc = Px4Process(_fake(tmp_path, mode, n), tmp_path, instance, tmp_path / "work", {})
    try:
        with proc:
            rec = run_lockstep(proc, server, link, schedule, P, actuation, rotors, sensors,
                               3.0, connect_timeout, answer_timeout)
    finally:
        link.close()
        server.close()
    assert not proc.alive()                          # never left behind
    return rec


def test_px4_dies_mid_flight_keeps_what_it_has(tmp_path):
    rec = _fly(tmp_path, "answer then exit", n=150)
    assert rec.partial and "PX4 died" in rec.reason and "exit code 3" in rec.reason
    # it answered 150 steps of 4 ms: about 0.6 s flown, on the ground (disarmed, zeros)
    assert 0.5 < rec.n * rec.dt < 0.7
    assert np.isfinite(rec.x[:rec.n]).all() and np.all(rec.x[:rec.n, 2] == 0.0)


def test_px4_stops_answering(tmp_path):
    with pytest.raises(Px4TimeoutError, match=r"stopped answering.*within 0.5 s.*still runs"):
        _fly(tmp_path, "answer then hang", n=100, answer_timeout=0.5)


def test_px4_never_connects(tmp_path):
    with pytest.raises(Px4TimeoutError, match=r"did not connect .*4\d\d\d within 0.5 s"):
        _fly(tmp_path, "hang", connect_timeout=0.5)


def test_px4_exits_before_connecting(tmp_path):
    with pytest.raises(Px4Error, match=r"PX4 ended before it connected .*exit code 4"):
        _fly(tmp_path, "exit")
