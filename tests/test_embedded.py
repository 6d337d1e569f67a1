"""The exported C99 controllers on the host: golden files, the promised C contract, the double
closed loop against the Python compiled path (1e-9), float32 against double, a new controller
exported with no new code, and the `quadcog export` command."""
import dataclasses
import os
from pathlib import Path
import re
import subprocess
import sys

import casadi as ca
import numpy as np
import pytest

from quadcog.cli import main as cli
from quadcog.controllers import make_controller
from quadcog.controllers.base import Controller
from quadcog.embedded import ExportError, export_controller
from quadcog.embedded.emit import literal
from quadcog.embedded.host import HostStep, build_host_library, fly
from quadcog.embedded.make_embedded import CONTROLLERS
from quadcog.scenarios.scenario import load_scenario

ROOT = Path(__file__).resolve().parent.parent
EMBEDDED = ROOT / "generated" / "embedded"


@pytest.fixture(scope="module")
def libraries(tmp_path_factory):
    """One host library per precision from the committed modules (strict flags: a warning
    fails the build)."""
    tmp = tmp_path_factory.mktemp("embedded-host")
    return {p: build_host_library(EMBEDDED / p, CONTROLLERS, tmp / f"{p}.so")
            for p in ("double", "float32")}


@pytest.fixture(scope="module")
def flights():
    """The Python compiled-path flights: fig6 and fig7 with each controller."""
    out = {}
    for fig in ("fig6", "fig7"):
        sc = load_scenario(fig)
        for name in CONTROLLERS:
            s = dataclasses.replace(sc, controller=name, controller_params=(
                sc.controller_params if name == "adaptive" else {}))
            out[fig, name] = s, s.run()
    return out


def test_generated_embedded_is_fresh_and_seed_independent():
    """generated/embedded/ is byte for byte what the exporter writes, under another hash seed."""
    env = dict(os.environ, PYTHONHASHSEED="4242")
    res = subprocess.run([sys.executable, "-m", "quadcog.embedded", "--check"], cwd=ROOT,
                         env=env, capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr


@pytest.mark.parametrize("precision", ["double", "float32"])
@pytest.mark.parametrize("name", CONTROLLERS)
def test_c_contract(name, precision):
    """Includes, entry points, no state outside c, and float32 that is really float32."""
    h = (EMBEDDED / precision / f"quadcog_{name}.h").read_text()
    c = (EMBEDDED / precision / f"quadcog_{name}.c").read_text()
    for text in (h, c):
        assert text.startswith("/* DO NOT EDIT: written by `make embedded` from")
    assert re.findall(r"#include\s*(\S+)", c) == ["<math.h>", f'"quadcog_{name}.h"']
    assert re.findall(r"#include", h) == []
    nc = make_controller(name).n_state
    assert f"#define QUADCOG_{name.upper()}_NC {nc}\n" in h
    assert re.search(rf"void quadcog_{name}_step\(const qc_real x\[12\], const qc_real ref\[14\], "
                     r"qc_real c\[\],\s+qc_real dt, qc_real U\[4\]\);", h)
    assert f"void quadcog_{name}_init(qc_real c[]);" in h
    code = re.sub(r"/\*.*?\*/", "", c, flags=re.S)
    assert not re.search(r"\b(static|malloc|free|printf|extern)\b", code)
    assert f"typedef {'float' if precision == 'float32' else 'double'} qc_real;" in h
    if precision == "float32":
        assert not re.search(r"\bdouble\b", code)
        numbers = re.findall(r"(?<![\w.])(\d+\.\d*(?:e[+-]?\d+)?)(f?)", code)
        assert numbers and all(f == "f" for _, f in numbers), "a double literal in float32 code"
        calls = set(re.findall(r"\b([a-z0-9]+)\(", code)) - {"void"}
        assert calls and all(fn.endswith("f") for fn in calls), calls
    # the nominal mass and the poles are documented in the header, with units
    assert re.search(r"\*\s+m\s+= 0\.68 kg", h) and "Designed for" in h


def test_literals_round_trip():
    """float32 literals are the float32 nearest the value; double literals keep 15 digits."""
    rng = np.random.default_rng(1)
    for v in np.concatenate([rng.normal(size=200) * 10.0 ** rng.integers(-8, 8, 200),
                             [0.0, 1.0, -2.5, 9.81, 1e-30]]):
        f = literal(v, "float32")
        assert f.endswith("f") and np.float32(f[:-1]) == np.float32(v), (v, f)
        d = float(literal(v, "double"))
        assert abs(d - v) <= 5e-15 * abs(v), (v, d)


def _max_diff(a, b):
    """Largest difference relative to max(1, largest |b|): a diverging flight's rates reach
    hundreds of rad/s."""
    return float(np.max(np.abs(a - b))) / max(1.0, float(np.max(np.abs(b)))) if a.size else 0.0


@pytest.mark.slow
@pytest.mark.parametrize("fig", ["fig6", "fig7"])
def test_double_closed_loop_equals_python_path(libraries, flights, fig):
    """The exported double steps, flown with the double truth plant, reproduce the Python
    compiled path (same step: law, held input, RK4, Euler update with projection) to 1e-9."""
    for name in CONTROLLERS:
        sc, res = flights[fig, name]
        nc = make_controller(name).n_state
        X, C, _ = fly(HostStep(libraries["double"], name, "double", nc), res, sc)
        assert len(X) == len(res.t)
        assert _max_diff(X, res.x) <= 1e-9, (fig, name, _max_diff(X, res.x))
        if getattr(sc.make_controller(), "estimates_cog", False):
            assert _max_diff(C[:, :3], res.r_hat) <= 1e-9, (fig, name)


@pytest.mark.slow
@pytest.mark.parametrize("fig", ["fig6", "fig7"])
def test_float32_closed_loop_stays_with_double(libraries, flights, fig):
    """float32 flights: tail RMS error within 1 mm of the double flight's, r_hat within 1 %."""
    for name in CONTROLLERS:
        sc, res = flights[fig, name]
        nc = make_controller(name).n_state
        X, C, metrics = fly(HostStep(libraries["float32"], name, "float32", nc), res, sc)
        assert len(X) == len(res.t) and np.isfinite(X).all()
        if res.metrics.diverged:      # FL on fig6 (rotors only push): the same divergence
            err = np.linalg.norm(X[:, :3] - res.x[:, :3], axis=1)
            early = res.t <= res.t[-1] - 0.1
            assert err[early].max() <= 1e-3, (fig, name, err[early].max())
            continue
        tail64 = res.metrics.rms_position_error_tail
        assert abs(metrics["rms_position_error_tail"] - tail64) <= 1e-3, (fig, name)
        if getattr(sc.make_controller(), "estimates_cog", False):
            r64, r32 = res.r_hat[-1], C[-1][:3]
            assert np.linalg.norm(r32 - r64) <= 0.01 * np.linalg.norm(r64), (fig, name, r32, r64)


class TwoStateLaw(Controller):
    """A controller unknown to the exporter: a PD-like law with a 2-entry state that
    integrates the x and y position errors and is projected onto |c| <= 0.5."""
    name = "two_state_law"
    n_state = 2

    def expression(self, t, x, ref, c):
        e = x[0:2] - ref[0:2]
        U = ca.vertcat(6.67 - 2.0 * (x[2] - ref[2]) + ca.sin(x[3]), -0.3 * x[3] - 0.1 * c[1],
                       -0.3 * x[4] + 0.1 * c[0], ca.atan2(x[5], 1.0 + x[11] ** 2))
        return U, 3.0 * e

    def initial_state(self):
        return np.array([0.1, -0.2])

    def project(self, c):
        n = ca.norm_2(c)
        return ca.if_else(n > 0.5, c * (0.5 / n), c)


def test_any_controller_exports_without_new_code(tmp_path):
    """A new controller class exports through the public interface alone, and its C step equals
    law + Euler step + projection evaluated by CasADi (double) at random points."""
    ctl = TwoStateLaw()
    export_controller(ctl, "double", tmp_path, name="twostate")
    step = HostStep(build_host_library(tmp_path, ["twostate"], tmp_path / "lib.so"),
                    "twostate", "double", 2)
    assert np.allclose(step.init()[:2], [0.1, -0.2])
    law = ctl.function()
    rng = np.random.default_rng(3)
    projected = 0
    for _ in range(50):
        x, ref = rng.normal(size=12), rng.normal(size=14)
        c0 = rng.normal(size=2) * 0.4
        dt = 0.05
        step.c[:2] = c0
        U = step.step(x, ref, dt)
        U_ref, c_dot = (np.array(v).ravel() for v in law(0.0, x, ref, c0))
        c_next = c0 + dt * c_dot
        if np.linalg.norm(c_next) > 0.5:             # the projection, written out here
            c_next *= 0.5 / np.linalg.norm(c_next)
            projected += 1
        assert np.allclose(U, U_ref, rtol=1e-12, atol=1e-12)
        assert np.allclose(step.c[:2], c_next, rtol=1e-12, atol=1e-12)
    assert projected > 0


def test_time_dependent_law_is_refused():
    class Clocked(TwoStateLaw):
        def expression(self, t, x, ref, c):
            U, c_dot = super().expression(t, x, ref, c)
            return U + t, c_dot
    with pytest.raises(ExportError, match="two_state_law.*depends on the time"):
        export_controller(Clocked(), "float32", "/nonexistent-never-written")


def test_cli_export(tmp_path, capsys):
    assert cli(["export", "--controller", "pd", "--precision", "float32",
                "--out", str(tmp_path)]) == 0
    for name in ("quadcog_pd.h", "quadcog_pd.c"):       # the committed module but its writer
        first, *rest = (tmp_path / name).read_text().splitlines(True)
        assert rest == (EMBEDDED / "float32" / name).read_text().splitlines(True)[1:]
        assert "written by `quadcog export --controller pd --precision float32" in first
    with pytest.raises(SystemExit):
        cli(["export", "--controller", "pd", "--precision", "half", "--out", str(tmp_path)])
    assert "half" in capsys.readouterr().err
    assert cli(["export", "--controller", "lqr", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "lqr" in err and "adaptive" in err
