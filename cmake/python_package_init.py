
# Appended by pidlab's build (cmake/python_package_init.py) to lcm-gen's
# __init__.py: the package `pidlab` also holds pidlab.evaluate,
# pidlab.tune, pidlab.identify and pidlab.autotune, from the C++ module _pidlab (tools/python/, docs/python.md)
# when it is built (-DPIDLAB_BUILD_PYTHON=ON, the default).
try:
    from ._pidlab import evaluate, tune, identify, autotune, read_spec, spec_fields, __version__  # noqa: F401
except ModuleNotFoundError:
    pass
