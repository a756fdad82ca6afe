# SPDX-License-Identifier: Apache-2.0
"""envpis.__version__ is the CMake project version, read here from the top-level CMakeLists.txt so that
bumping project(envpis VERSION ...) without rebuilding the module, or a module that invents its own
version, fails."""
import pathlib
import re

import envpis

ROOT = pathlib.Path(__file__).resolve().parents[2]


def project_version():
    text = (ROOT / "CMakeLists.txt").read_text()
    match = re.search(r"project\(\s*envpis\s+VERSION\s+([0-9]+\.[0-9]+\.[0-9]+)", text)
    assert match, "no project(envpis VERSION x.y.z) in CMakeLists.txt"
    return match.group(1)


def test_version_is_the_cmake_project_version():
    assert isinstance(envpis.__version__, str)
    assert envpis.__version__ == project_version()
