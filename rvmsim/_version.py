"""rvmsim's version (pyproject.toml's ``version`` says the same; a test checks it)."""

__version__ = "0.1.0"
