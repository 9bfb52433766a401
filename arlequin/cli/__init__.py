"""The ``arlequin`` command (:func:`main`), generated from the demos' configurations."""

from .main import main

__all__ = ["main"]
