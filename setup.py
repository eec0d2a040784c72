"""The optional compiled accelerator (src/opentmcl/_accel.c, docs/performance.md "Compiled accelerator").

Everything else of the package is declared in pyproject.toml. The extension is optional: on a
machine without a C compiler (or without Python's headers) the build of it fails quietly and the
pure-Python package is installed; `opentmcl.accel.active()` is then False.
"""
from setuptools import Extension, setup

setup(ext_modules=[Extension("opentmcl._accel", ["src/opentmcl/_accel.c"], optional=True)])
