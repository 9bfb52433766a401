"""How the vectors of a coupled system map onto meshes: the content of the field series.

A :class:`FieldLayout` lists, per block, its mesh and components, the static per-cell data to
show with it (the partition weight ``alpha`` of the block), and, per mediator, the block whose
nodes carry its multipliers. :meth:`FieldLayout.frame` turns a global displacement, velocity and
the multipliers into point and cell data per block (vectors padded to 3 components).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..dofs import DofMap
from .fields import pad_vectors

__all__ = ["BlockFields", "FieldLayout"]

_UNITS = {
    "displacement": "m",
    "velocity": "m/s",
    "alpha": "1",
    "multiplier": "N/m^3 (N/m for 1D bars): nodal values of the mediator field λ, whose "
    "force on the coarse model is −C_cᵀλ (N)",
}


@dataclass
class BlockFields:
    """One block's mesh and its static data.

    Attributes
    ----------
    name : str
    mesh : skfem.Mesh
    n_components : int
    cell_data : dict
        Name -> per-cell values (n_cells,) written with every frame (e.g. ``alpha``).
    """

    name: str
    mesh: Any
    n_components: int
    cell_data: dict[str, np.ndarray] = field(default_factory=dict)


@dataclass
class FieldLayout:
    """Blocks with meshes and the mediators' multiplier fields.

    Attributes
    ----------
    blocks : list of BlockFields
    multipliers : dict
        Constraint name -> (block name, local dofs of that block carrying the multipliers,
        in the order of the multiplier vector).
    units : dict
        Field name -> unit (SI).
    """

    blocks: list[BlockFields]
    multipliers: dict[str, tuple[str, np.ndarray]] = field(default_factory=dict)
    units: dict[str, str] = field(default_factory=lambda: dict(_UNITS))

    @classmethod
    def of_system(cls, system: Any) -> FieldLayout:
        """The blocks of a system whose model has a mesh (weights 1, no mediators)."""
        blocks = []
        for b in system.blocks:
            mesh = getattr(b.model, "mesh", None)
            if mesh is not None:
                n_c = int(getattr(b.model, "n_components", 1))
                blocks.append(BlockFields(b.name, mesh, n_c))
        return cls(blocks)

    def frame(
        self,
        dofmap: DofMap,
        u: np.ndarray,
        v: np.ndarray | None = None,
        multipliers: Mapping[str, np.ndarray] | None = None,
    ) -> dict[str, tuple[dict[str, np.ndarray], dict[str, np.ndarray]]]:
        """Block name -> (point data, cell data) at one time."""
        out = {}
        for bf in self.blocks:
            sl = dofmap[bf.name].slice
            point = {"displacement": pad_vectors(u[sl], bf.n_components)}
            if v is not None:
                point["velocity"] = pad_vectors(v[sl], bf.n_components)
            out[bf.name] = (point, dict(bf.cell_data))
        for cname, (bname, dofs) in self.multipliers.items():
            if bname not in out or multipliers is None or cname not in multipliers:
                continue
            bf = next(b for b in self.blocks if b.name == bname)
            nodal = np.zeros(dofmap[bname].size)
            nodal[dofs] = multipliers[cname]
            out[bname][0][f"multiplier:{cname.split(':')[-1]}"] = pad_vectors(
                nodal, bf.n_components
            )
        return out
