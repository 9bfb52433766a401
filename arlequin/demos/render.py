"""Off-screen rendering with pyvista, shared by the demos' pictures (PNG).

pyvista renders through VTK's off-screen path (EGL with the pip wheel) when
``pyvista.OFF_SCREEN`` is set, so no display is needed. The demos' own pictures live in their
packages (the Taylor bar's in :mod:`arlequin.demos.taylor_bar.render`).
"""

from __future__ import annotations

import os

__all__: list[str] = []


def _offscreen():
    """pyvista, off-screen; without a display, VTK's EGL window directly (it would try X first
    and print a warning)."""
    if not os.environ.get("DISPLAY"):
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    import pyvista as pv

    pv.OFF_SCREEN = True
    return pv
