"""Rigid obstacles given by level-set functions: φ(x) (m), φ > 0 in free space.

A contact pair against an obstacle (:class:`arlequin.models.RigidContactPair`) takes the signed
distance ``d_n = −φ(x)`` (negative when apart) and the normal ``∇φ/|∇φ|`` at each collocation
point; φ should be a signed distance near the surface for the reported gaps to be distances.
Points are arrays of shape (dim, m), in m.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = ["LevelSetObstacle", "Obstacle", "PlaneObstacle", "SphereObstacle"]


class Obstacle:
    """A rigid obstacle given by a level-set function φ (m), φ > 0 in free space.

    Subclasses implement :meth:`phi` and :meth:`gradient`; points are arrays of shape (dim, m).

    Attributes
    ----------
    constant_normal : bool
        The gradient is the same at every point (a plane): a contact pair then computes the
        normals and the velocity-jump rows once, not at every step. False unless a subclass
        knows it.
    """

    constant_normal: bool = False

    def phi(self, x: np.ndarray) -> np.ndarray:
        """φ(x) (m), shape (m,)."""
        raise NotImplementedError

    def gradient(self, x: np.ndarray) -> np.ndarray:
        """∇φ(x) (dimensionless), shape (dim, m)."""
        raise NotImplementedError


class PlaneObstacle(Obstacle):
    """Half-space obstacle: free space is ``n·(x − p) > 0``.

    Parameters
    ----------
    point : array_like, shape (dim,)
        A point of the plane (m).
    normal : array_like, shape (dim,)
        Normal pointing into free space (normalised here).
    """

    constant_normal = True

    def __init__(self, point, normal) -> None:
        self.point = np.asarray(point, dtype=float).ravel()
        n = np.asarray(normal, dtype=float).ravel()
        norm = float(np.linalg.norm(n))
        if not norm > 0.0 or n.size != self.point.size:
            raise ValueError(
                f"plane normal must be non-zero with {self.point.size} components, got {normal}"
            )
        self.normal = n / norm

    def phi(self, x: np.ndarray) -> np.ndarray:
        return self.normal @ (np.asarray(x, dtype=float) - self.point[:, None])

    def gradient(self, x: np.ndarray) -> np.ndarray:
        return np.repeat(self.normal[:, None], np.asarray(x).shape[1], axis=1)


class SphereObstacle(Obstacle):
    """Rigid ball (``inside=False``: free space outside) or spherical cavity (``inside=True``).

    Parameters
    ----------
    center : array_like, shape (dim,)
        Centre (m); a circle in 2D, a point pair in 1D.
    radius : float
        Radius (m), > 0.
    inside : bool
        Free space is inside the sphere (a container) instead of outside.
    """

    def __init__(self, center, radius: float, inside: bool = False) -> None:
        self.center = np.asarray(center, dtype=float).ravel()
        if not radius > 0.0:
            raise ValueError(f"sphere radius must be positive, got radius={radius}")
        self.radius = float(radius)
        self.sign = -1.0 if inside else 1.0

    def _r(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        rel = np.asarray(x, dtype=float) - self.center[:, None]
        r = np.sqrt(np.sum(rel * rel, axis=0))
        return rel, r

    def phi(self, x: np.ndarray) -> np.ndarray:
        _, r = self._r(x)
        return self.sign * (r - self.radius)

    def gradient(self, x: np.ndarray) -> np.ndarray:
        rel, r = self._r(x)
        if np.any(r == 0.0):
            raise ValueError("sphere obstacle: gradient undefined at the centre")
        return self.sign * rel / r


class LevelSetObstacle(Obstacle):
    """Obstacle from callables ``phi(x) -> (m,)`` and ``gradient(x) -> (dim, m)``, x: (dim, m)."""

    def __init__(
        self, phi: Callable[[np.ndarray], np.ndarray], gradient: Callable[[np.ndarray], np.ndarray]
    ) -> None:
        self._phi = phi
        self._grad = gradient

    def phi(self, x: np.ndarray) -> np.ndarray:
        return np.asarray(self._phi(x), dtype=float).reshape(np.asarray(x).shape[1])

    def gradient(self, x: np.ndarray) -> np.ndarray:
        return np.asarray(self._grad(x), dtype=float).reshape(np.asarray(x).shape)
