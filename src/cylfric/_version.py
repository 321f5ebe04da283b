"""The version, read by setuptools at build time (pyproject.toml: dynamic version) and by
``cylfric.__version__`` without importlib.metadata (which costs about 0.1 s per process)."""

__version__ = "0.1.0"
