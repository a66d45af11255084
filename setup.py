"""Build the compiled kernels (activecontour/_kernels.pyx) ahead of time; metadata is in pyproject.toml."""

from Cython.Build import cythonize
from setuptools import Extension, setup

setup(
    ext_modules=cythonize(
        [Extension("activecontour._kernels", ["activecontour/_kernels.pyx"])],
        compiler_directives={"language_level": 3},
    )
)
