"""The sample flight logs shipped inside the package (quadcog.logs.samples): the docs' examples
find them through the package from any folder, the wheel would carry them with their licence,
they are the very bytes of the CrazyPAD files in tests/data, and a wrong name is refused."""
from fnmatch import fnmatch
import os
from pathlib import Path
import re
import subprocess
import sys
import tomllib

import pytest

from quadcog.errors import LogError
from quadcog.logs.samples import SAMPLE_FOLDER, resolve_log_argument, sample, sample_logs, sample_names

ROOT = Path(__file__).resolve().parent.parent


def test_samples_are_the_crazypad_files_with_their_licence():
    names = sample_names()
    assert len(names) == 5, names
    for name in names:
        copy = ROOT / "tests" / "data" / name
        assert sample(name).read_bytes() == copy.read_bytes(), name
    folder = SAMPLE_FOLDER / "crazypad"
    assert (folder / "LICENSE").read_bytes() == (ROOT / "tests/data/crazypad/LICENSE").read_bytes()
    readme = (folder / "README.md").read_text()
    assert "doi:10.3390/data9060079" in readme and "MIT" in readme
    for name in names:                       # the README's table names every shipped file
        assert name.rsplit("/", 1)[-1] in readme and name.split("/")[2] in readme
    total = sum(sample(n).stat().st_size for n in names)
    assert total < 1_500_000, f"{total} bytes of samples: keep the wheel small"


def test_pyproject_ships_every_sample_file():
    """Every file under sample_data/ is in a listed package and matched by its package-data
    globs (else the wheel silently lacks it; tests/test_install.py checks the built wheel)."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    for path in SAMPLE_FOLDER.rglob("*"):
        if not path.is_file():
            continue
        package = ".".join(path.parent.relative_to(ROOT).parts)
        assert package in config["packages"], package
        globs = config["package-data"].get(package, [])
        assert any(fnmatch(path.name, g) for g in globs), f"{path}: not in {package}'s {globs}"


def test_names_folders_and_refusals():
    folder = sample_logs("crazypad/motor_data/normal_flight")
    assert [p.name for p in folder] == ["E8_log00", "E8_log01"]
    assert resolve_log_argument("sample:crazypad/motor_data/normal_flight/E8_log01") == \
        [folder[1]]
    assert resolve_log_argument("my/log.bin") == [Path("my/log.bin")]
    for bad in ("crazypad/nothing", "../../errors.py", "", "crazypad/README.md", 3):
        with pytest.raises(LogError, match="no sample log of quadcog; expected one of crazypad"):
            sample(bad)


def test_cli_refuses_an_unknown_sample(tmp_path):
    res = subprocess.run([sys.executable, "-m", "quadcog", "identify", "sample:crazypad/E1"],
                         cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert res.returncode != 0
    assert "'crazypad/E1' is no sample log of quadcog" in res.stderr, res.stderr
    assert "Traceback" not in res.stderr


def test_docs_example_finds_its_log_through_the_package(tmp_path):
    """The first block of the logs page, run as a reader with a wheel would: from a folder
    outside the checkout that has no tests/data; the log it reads is the package's."""
    page = (ROOT / "docs" / "logs.md").read_text()
    block = re.search(r"^```python\n(.*?)^```", page, flags=re.S | re.M).group(1)
    assert 'sample("crazypad' in block and "tests/data" not in block
    script = tmp_path / "block.py"
    script.write_text(block + "print(log.source)\n")
    env = dict(os.environ, MPLBACKEND="Agg")
    env.pop("PYTHONPATH", None)
    res = subprocess.run([sys.executable, str(script)], cwd=tmp_path, env=env,
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    assert not (tmp_path / "tests").exists() and not tmp_path.is_relative_to(ROOT)
    source = Path(res.stdout.strip().splitlines()[-1]).resolve()
    assert source.is_relative_to(SAMPLE_FOLDER), source
    assert (tmp_path / "flight.csv").is_file()
