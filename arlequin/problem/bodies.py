"""Several bodies in one coupled system: each an Arlequin problem (a coarse model, zero or more
patches) or a bare model, assembled block-diagonally with one dof vector and one stable step.

Usage
-----
>>> bodies = MultiBodyProblem({"ball": ball_problem, "block": block_problem})
>>> system = bodies.system()
>>> bodies.block_name("ball", "patch")
'ball.patch'
>>> surface = ContactSurface(mesh, where=..., offset=system.dofmap["ball.patch"])

The blocks of body ``b`` are named ``"b.<block>"`` (``"ball.coarse"``, ``"ball.patch"``; a bare
model is the single block ``"b.model"``). Each body's couplings, Dirichlet conditions and loads
are its problem's, moved to the body's place in the global vector; the bodies interact only
through the unilateral constraints (contact pairs) given to the integrator, built on the
assembled system's dof map. Units are SI.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..contract import ContractError, Model, check_protocol
from ..io.layout import BlockFields, FieldLayout
from .system import Block, BlockTerm, CoupledSystem, LinearConstraint

__all__ = ["MultiBodyProblem"]

#: Separator between a body's name and its block's in the assembled system.
SEPARATOR = "."


def _is_problem(body: Any) -> bool:
    return callable(getattr(body, "system", None)) and callable(getattr(body, "field_layout",
                                                                        None))  # fmt: skip


def _join(body: str, block: str) -> str:
    return f"{body}{SEPARATOR}{block}"


def _shift_columns(matrix: sp.spmatrix, offset: int, n: int) -> sp.csr_matrix:
    """The rows of ``matrix`` (m, n_b) acting on the columns offset…offset + n_b of (m, n)."""
    coo = sp.coo_matrix(matrix)
    return sp.csr_matrix((coo.data, (coo.row, coo.col + offset)), shape=(coo.shape[0], n))


class MultiBodyProblem:
    """Bodies, each an :class:`~arlequin.ArlequinProblem` or a model, in one system.

    Parameters
    ----------
    bodies : mapping
        Body name -> :class:`~arlequin.ArlequinProblem` (or anything with ``system()``,
        ``field_layout()`` and ``model("coarse")``) or a bare model (one block ``"model"``,
        weight 1, no conditions).

    Raises
    ------
    ValueError
        No body, a name with the separator ``"."`` in it, or bodies of different dimensions.
    """

    def __init__(self, bodies: Mapping[str, Any]) -> None:
        if not bodies:
            raise ValueError("a multi-body problem needs at least one body")
        self.bodies = dict(bodies)
        dims = {}
        for name, body in self.bodies.items():
            if not isinstance(name, str) or not name or SEPARATOR in name:
                raise ValueError(f"body names must be non-empty strings without "
                                 f"{SEPARATOR!r}, got {name!r}")  # fmt: skip
            if _is_problem(body):
                model = body.model("coarse")
            else:
                check_protocol(body, Model, f"body {name!r} (an ArlequinProblem or a model)")
                model = body
            dims[name] = (int(model.mesh.dim()), getattr(model, "kind", None))
        if len({d for d, _ in dims.values()}) > 1 or len({k for _, k in dims.values()}) > 1:
            raise ValueError(f"the bodies' meshes have different dimensions or kinds (plane "
                             f"strain, axisymmetric...): {dims}")  # fmt: skip
        self._systems: dict[str, CoupledSystem] | None = None

    def block_name(self, body: str, block: str | None = None) -> str:
        """The assembled name of a body's block (``"ball.patch"``); ``block`` None: the body's
        first block (``"coarse"`` of a problem, ``"model"`` of a bare model).

        Raises
        ------
        ValueError
            An unknown body or block, naming the known ones.
        """
        if body not in self.bodies:
            raise ValueError(f"unknown body {body!r}; bodies are {list(self.bodies)}")
        names = [b.name for b in self.body_systems()[body].blocks]
        if block is None:
            block = names[0]
        if block not in names:
            raise ValueError(f"body {body!r} has no block {block!r}; its blocks are {names}")
        return _join(body, block)

    def body_systems(self) -> dict[str, CoupledSystem]:
        """Each body's own coupled system (built once)."""
        if self._systems is None or None in self._systems.values():
            out = {}
            for name, body in self.bodies.items():
                if self._systems is not None and self._systems.get(name) is not None:
                    out[name] = self._systems[name]
                elif _is_problem(body):
                    out[name] = body.system()
                else:
                    out[name] = CoupledSystem([Block("model", body, [BlockTerm(body)])])
            self._systems = out
        return self._systems

    @property
    def block_names(self) -> list[str]:
        """Every block of the assembled system, body by body."""
        return [_join(b, blk.name) for b, s in self.body_systems().items() for blk in s.blocks]

    def system(self) -> CoupledSystem:
        """The assembled system: the bodies' blocks, constraints and loads side by side."""
        systems = self.body_systems()
        blocks = [Block(_join(b, blk.name), blk.model, blk.terms)
                  for b, s in systems.items() for blk in s.blocks]  # fmt: skip
        offsets = {}
        n = 0
        for b, s in systems.items():
            offsets[b] = n
            n += s.n_dofs
        constraints = []
        for b, s in systems.items():
            for c in s.constraints:
                if not isinstance(c, LinearConstraint):
                    raise ContractError(
                        f"body {b!r} has a constraint {c!r} that is not a "
                        "LinearConstraint: give contact to the integrator"
                    )
                pivots = None if c.pivot_dofs is None else c.pivot_dofs + offsets[b]
                constraints.append(LinearConstraint(
                    _shift_columns(c.matrix, offsets[b], n), c.rhs, f"{b}{SEPARATOR}{c.name}",
                    level=c.level, kind=c.kind, pivot_dofs=pivots))  # fmt: skip
        loaded = [(offsets[b], s) for b, s in systems.items() if s.load is not None]

        def load(t: float) -> np.ndarray:
            f = np.zeros(n)
            for off, s in loaded:
                f[off : off + s.n_dofs] = s.external_force(t)
            return f

        out = CoupledSystem(blocks, constraints, load if loaded else None,
                            band_plasticity=self.band_plasticity)  # fmt: skip
        for b, s in systems.items():  # the operators computed once, on the body's system
            for blk in s.blocks:
                out.share_block(_join(b, blk.name), s, blk)
        return out

    def band_plasticity(self, states: dict[str, list[Any]]) -> list[Any]:
        """Plastic flow in the gluing bands of every body's J2 patches for the blocks'
        ``states`` (assembled names), each named by its assembled block name
        (:meth:`ArlequinProblem.band_plasticity`)."""
        out = []
        for name, body in self.bodies.items():
            measure = getattr(body, "band_plasticity", None)
            if not callable(measure):
                continue
            prefix = _join(name, "")
            own = {k[len(prefix) :]: v for k, v in states.items() if k.startswith(prefix)}
            out += [replace(band, patch=_join(name, band.patch)) for band in measure(own)]
        return out

    def with_body(self, name: str, body: Any) -> MultiBodyProblem:
        """The problem with body ``name`` replaced by ``body`` (its patch grown), the other
        bodies' systems (and their operators, computed once) kept."""
        if name not in self.bodies:
            raise ValueError(f"unknown body {name!r}; bodies are {list(self.bodies)}")
        new = MultiBodyProblem({**self.bodies, name: body})
        kept = self.body_systems()
        new._systems = {b: kept[b] if b != name else None for b in new.bodies}
        return new

    def field_layout(self) -> FieldLayout:
        """Each body's fields (its problem's layout) under the assembled block names."""
        blocks, multipliers = [], {}
        for b, body in self.bodies.items():
            layout = (body.field_layout() if _is_problem(body)
                      else FieldLayout.of_system(self.body_systems()[b]))  # fmt: skip
            for bf in layout.blocks:
                blocks.append(BlockFields(_join(b, bf.name), bf.mesh, bf.n_components,
                                          dict(bf.cell_data)))  # fmt: skip
            for key, (carrier, dofs) in layout.multipliers.items():
                multipliers[_join(b, key)] = (_join(b, carrier), dofs)
        return FieldLayout(blocks, multipliers)
