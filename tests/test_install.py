"""quadcog installs and works outside its checkout: a wheel (built from the tree and from the
sdist) in a fresh virtual environment runs a shipped scenario from a temporary folder, and
the editable install of the test environment is checked from a foreign directory in
test_packaging.py.

The fresh environment has no pip and no network: the package is installed by this
environment's pip (``pip --python``), and its dependencies (numpy, CasADi, ...) are made
visible through a .pth line pointing at this environment's site-packages, which holds no
quadcog package (the editable install is a finder hook that a plain .pth line never runs).
The test proves that quadcog is imported from the installed wheel, not from the checkout.
"""
from concurrent.futures import ThreadPoolExecutor
import json
import os
from pathlib import Path
import shutil
import subprocess
import sys
import sysconfig
import tarfile
import tomllib
import zipfile

from conftest import background_dir, background_job, background_result
import pytest

ROOT = Path(__file__).resolve().parent.parent
SKIP = shutil.ignore_patterns(".git", ".venv", "out", "build", "dist", "*.egg-info",
                              "__pycache__", ".pytest_cache", ".generated-*")


def _run(cmd, cwd, **kw):
    env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "HOME": str(Path.home())}
    for key in ("QUADCOG_CACHE_DIR", "XDG_CACHE_HOME", "CC"):
        if key in os.environ:
            env[key] = os.environ[key]
    res = subprocess.run([str(c) for c in cmd], cwd=cwd, capture_output=True, text=True,
                         env=env, timeout=300, **kw)
    assert res.returncode == 0, f"{' '.join(map(str, cmd))}\n{res.stdout}\n{res.stderr}"
    return res.stdout


def _wheel(src, out):
    _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
          "-w", out, src], cwd=src)
    (wheel,) = Path(out).glob("quadcog-*.whl")
    return wheel


def _build_wheels():
    """(wheel built from a copy of the tree, wheel built from the sdist of another copy), both
    builds at once; subprocesses and files only, started in the background at collection
    (conftest.background_job)."""
    tmp = background_dir("wheels")
    src, src_for_sdist = tmp / "src", tmp / "src-for-sdist"
    for folder in (src, src_for_sdist):        # one copy per build: they write into the tree
        shutil.copytree(ROOT, folder, ignore=SKIP)

    def via_sdist():
        _run([sys.executable, "-c", "from setuptools import build_meta as b; "
              f"print(b.build_sdist({str(tmp / 'sdist')!r}))"], cwd=src_for_sdist)
        (sdist,) = (tmp / "sdist").glob("quadcog-*.tar.gz")
        with tarfile.open(sdist) as tar:
            tar.extractall(tmp / "unpacked", filter="data")
        (unpacked,) = (tmp / "unpacked").iterdir()
        return _wheel(unpacked, tmp / "wheel-from-sdist")

    with ThreadPoolExecutor(max_workers=2) as pool:
        from_tree, from_sdist = pool.submit(_wheel, src, tmp / "wheel"), pool.submit(via_sdist)
        return from_tree.result(), from_sdist.result()


background_job("install: wheels", __file__, "wheels", lambda: _build_wheels)


@pytest.fixture(scope="module")
def wheels():
    """(wheel built from the tree, wheel built from the sdist)."""
    return background_result("install: wheels")


def test_every_package_is_listed():
    """pyproject.toml lists the packages by hand: every folder of quadcog/ that holds files
    and every subfolder of generated/ must be there (else the wheel silently lacks it)."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(config["packages"])
    assert config["package-dir"] == {"quadcog._generated": "generated"}
    needed = set()
    for base, name in ((ROOT / "quadcog", "quadcog"), (ROOT / "generated", "quadcog._generated")):
        for folder in [base, *sorted(p for p in base.rglob("*") if p.is_dir())]:
            rel = folder.relative_to(base).parts
            if "__pycache__" in rel or not any(p.is_file() for p in folder.iterdir()):
                continue
            needed.add(".".join((name, *rel)))
    missing = sorted(needed - listed)
    assert not missing, (f"add {missing} to [tool.setuptools] packages in pyproject.toml")
    assert not sorted(listed - needed), "pyproject.toml lists packages that do not exist"


@pytest.mark.slow
def test_wheel_and_sdist_ship_the_generated_files(wheels):
    manifest = json.loads((ROOT / "generated" / "manifest.json").read_text())
    expected = {f"quadcog/_generated/{rel}" for rel in manifest["files"]}
    expected |= {"quadcog/_generated/manifest.json"}
    expected |= {f"quadcog/scenarios/{p.name}" for p in (ROOT / "quadcog/scenarios").glob("*")
                 if p.is_file()}
    # the sample logs of the docs' examples (quadcog.logs.samples), with their licence
    samples = ROOT / "quadcog" / "logs" / "sample_data"
    expected |= {p.relative_to(ROOT).as_posix() for p in samples.rglob("*") if p.is_file()}
    assert len([n for n in expected if "/sample_data/" in n]) == 7
    listings = []
    for wheel in wheels:
        with zipfile.ZipFile(wheel) as z:
            names = set(z.namelist())
            missing = expected - names
            assert not missing, (f"{wheel.name} lacks {sorted(missing)}: add the file type to "
                                 "[tool.setuptools.package-data] in pyproject.toml")
            for rel in manifest["files"]:      # the very bytes of generated/
                assert z.read(f"quadcog/_generated/{rel}") == (ROOT / "generated" / rel) \
                    .read_bytes(), rel
            # the licence pyproject names (MIT) and the citation file, in .dist-info/licenses/
            for name in ("LICENSE", "CITATION.cff"):
                shipped = [n for n in names if n.endswith(f".dist-info/licenses/{name}")]
                assert shipped, f"{wheel.name} lacks {name}: pyproject.toml license-files"
                assert z.read(shipped[0]) == (ROOT / name).read_bytes(), name
        assert "MIT License" in (ROOT / "LICENSE").read_text()
        listings.append(names - {n for n in names if ".dist-info/" in n})
    assert listings[0] == listings[1], "the wheel built from the sdist differs from the tree's"
    assert not any(n.startswith(("derive/", "tests/", "generated/")) for n in listings[0])


@pytest.mark.slow
def test_wheel_runs_a_scenario_in_a_fresh_venv(wheels, tmp_path):
    venv = tmp_path / "venv"
    _run([sys.executable, "-m", "venv", "--without-pip", venv], cwd=tmp_path)
    python = venv / "bin" / "python"
    site = Path(_run([python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                     cwd=tmp_path).strip())
    deps = {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}
    (site / "quadcog_test_dependencies.pth").write_text("\n".join(sorted(deps)) + "\n")
    _run([sys.executable, "-m", "pip", "--python", python, "install", "--no-deps", "--no-index",
          "-q", wheels[0]], cwd=tmp_path)
    work = tmp_path / "elsewhere"
    work.mkdir()
    where = json.loads(_run([python, "-c",
                             "import json, quadcog; m = quadcog.load(); print(json.dumps("
                             "[quadcog.__file__, str(m.folder), str(m.casadi_function('drift'))]))"],
                            cwd=work))
    assert Path(where[0]).is_relative_to(site / "quadcog"), where
    assert Path(where[1]) == (site / "quadcog" / "_generated").resolve(), where
    assert not Path(where[0]).is_relative_to(ROOT)
    out = _run([venv / "bin" / "quadcog", "run", "fig3a", "--out", "flight", "--no-plot",
                "--set", "duration=2"], cwd=work)     # the figure: tests/test_cli.py, same code
    metrics = json.loads((work / "flight" / "metrics.json").read_text())
    assert metrics["name"] == "fig3a" and not metrics["diverged"], out
    assert "fig3a" in _run([venv / "bin" / "quadcog", "scenarios"], cwd=work)
    # the docs' examples read the sample logs from the installed package, from any folder
    found = _run([python, "-c", "from quadcog.logs import read_log; from quadcog.logs.samples "
                  "import sample; print(read_log(sample('crazypad/motor_data/normal_flight/"
                  "E8_log00')).source)"], cwd=work).strip()
    assert Path(found).is_relative_to(site / "quadcog" / "logs" / "sample_data"), found
    out = _run([venv / "bin" / "quadcog", "identify", "sample:crazypad/motor_data/normal_flight"],
               cwd=work)
    assert "2 log(s)" in out, out

