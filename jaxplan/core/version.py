"""The installed version of jaxplan (`VERSION`, re-exported as ``jaxplan.__version__``) for modules inside jaxplan."""

from importlib.metadata import PackageNotFoundError, version

__all__ = ["VERSION"]

try:
    VERSION = version("jaxplan")
except PackageNotFoundError:  # pragma: no cover - running from a source tree without install
    VERSION = "0+unknown"
