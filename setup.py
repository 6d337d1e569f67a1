"""Packaging that pyproject.toml cannot say on its own: the committed top-level generated/
(the output of `make derive`) ships inside the package as ``quadcog._generated``, so that
an installed quadcog (wheel, sdist or editable) carries its own generated code. The data
files are listed in pyproject.toml under [tool.setuptools.package-data]."""
from pathlib import Path

from setuptools import find_namespace_packages, setup

GENERATED = ["quadcog._generated"] + [
    "quadcog._generated." + ".".join(d.relative_to("generated").parts)
    for d in sorted(Path("generated").rglob("*")) if d.is_dir()]

setup(packages=find_namespace_packages(include=["quadcog", "quadcog.*"],
                                       exclude=["*.__pycache__"]) + GENERATED,
      package_dir={"quadcog._generated": "generated"})
