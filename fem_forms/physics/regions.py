"""Which material each cell is made of ([[material]] `where`), and per-material values as DG0 fields: a
changed value refills a field and compiles nothing."""
from __future__ import annotations

from dolfinx import fem, mesh as dmesh
from mpi4py import MPI
import numpy as np
import ufl

from fem_forms.errors import InputError
from fem_forms.meshes import LoadedMesh
from fem_forms.physics import quadrature


class MaterialRegions:
    """The material index of every local cell (owned and ghost), the same on every rank count."""

    def __init__(self, loaded: LoadedMesh, materials: list):
        self.mesh = loaded.mesh
        self.materials = materials
        self.space = fem.FunctionSpace(self.mesh, ("DG", 0))
        imap = self.mesh.topology.index_map(self.mesh.topology.dim)
        self.n_owned, n_local = imap.size_local, imap.size_local + imap.num_ghosts
        self.index = self._assign(loaded, n_local)
        self._tags = None

    @property
    def several(self) -> bool:
        return len(self.materials) > 1

    def _claimed(self, loaded: LoadedMesh, m, n_local: int) -> np.ndarray:
        """A boolean per local cell: does material m's `where` claim it."""
        sel = m.where
        if sel.kind == "group":
            if sel.group not in loaded.cells:
                raise InputError(f"{sel.key}.group = {sel.group!r}: no such volume group (the mesh has: "
                                 f"{loaded.group_names()})")
            out = np.zeros(n_local, dtype=bool)
            out[loaded.cells[sel.group]] = True
            return out
        mid = dmesh.compute_midpoints(self.mesh, self.mesh.topology.dim, np.arange(n_local, dtype=np.int32))
        lo, hi = np.asarray(sel.lo), np.asarray(sel.hi)
        tol = 1e-9 * max(1.0, float(np.abs(np.concatenate([lo, hi])).max()))
        return np.all((mid >= lo - tol) & (mid <= hi + tol), axis=1)

    def _assign(self, loaded: LoadedMesh, n_local: int) -> np.ndarray:
        index = np.full(n_local, -1, dtype=np.int32)
        if not self.several and self.materials[0].where is None:
            index[:] = 0
            return index
        comm, own = self.mesh.comm, self.n_owned
        for i, m in enumerate(self.materials):
            if m.where is None:
                continue
            claimed = self._claimed(loaded, m, n_local)
            clash = claimed & (index >= 0)
            if comm.allreduce(int(clash[:own].sum()), op=MPI.SUM):
                other = self.materials[int(index[np.flatnonzero(clash)[0]])] if clash.any() else None
                raise InputError(f"{m.key}.where: claims cells another material already claims"
                                 + (f" ({other.key}, {other.name!r})" if other is not None else "")
                                 + "; regions must not overlap")
            if comm.allreduce(int(claimed[:own].sum()), op=MPI.SUM) == 0:
                raise InputError(f"{m.key}.where: claims no cell of the mesh (a box: cells whose centroid lies "
                                 "inside it)")
            index[claimed] = i
        rest = next((i for i, m in enumerate(self.materials) if m.where is None), None)
        left = comm.allreduce(int((index[:own] < 0).sum()), op=MPI.SUM)
        if rest is not None:
            if left == 0:
                raise InputError(f"{self.materials[rest].key}: no cell is left for it (the other materials "
                                 "claim every cell)")
            index[index < 0] = rest
        elif left:
            raise InputError(f"material: {left} cells belong to no material (give one [[material]] without "
                             "`where`: it takes every cell no other material claims)")
        return self._share_ghosts(index)

    def _share_ghosts(self, index: np.ndarray) -> np.ndarray:
        """Ghost cells take their owner's material (a group's local cells may list owned cells only)."""
        f = fem.Function(self.space)
        f.x.array[:] = index
        f.x.scatter_forward()
        return np.rint(f.x.array).astype(np.int32)

    def cell_values(self, values: list) -> np.ndarray:
        """One value (a number or an array) per local cell from one per material."""
        return np.asarray(values, dtype=float)[self.index]

    def field(self, values: list, name: str) -> fem.Function:
        """A DG0 Function holding each material's value (a number, or an array of any shape) on its cells."""
        shape = np.shape(values[0])
        space = self.space if shape == () else fem.TensorFunctionSpace(self.mesh, ("DG", 0), shape=shape) \
            if len(shape) == 2 else fem.VectorFunctionSpace(self.mesh, ("DG", 0), dim=shape[0])
        f = fem.Function(space, name=name)
        self.fill(f, values)
        return f

    def fill(self, f: fem.Function, values: list) -> None:
        f.x.array[:] = self.cell_values(values).ravel()

    def tags(self) -> dmesh.MeshTags:
        """Cell tags: material index + 1 on every local cell (a dx subdomain per material)."""
        if self._tags is None:
            cells = np.arange(len(self.index), dtype=np.int32)
            self._tags = dmesh.meshtags(self.mesh, self.mesh.topology.dim, cells, self.index + 1)
        return self._tags

    def summary(self, density: fem.Function, quadrature_degree: int = 2) -> list[dict]:
        """name, cells, volume (m^3) and mass (kg) of each material (reference configuration, all ranks)."""
        comm = self.mesh.comm
        dx = ufl.Measure("dx", domain=self.mesh, subdomain_data=self.tags(),
                         metadata=quadrature.metadata(self.mesh.topology.cell_name(), quadrature_degree))
        out = []
        for i, m in enumerate(self.materials):
            one = fem.Constant(self.mesh, 1.0)
            vol = comm.allreduce(fem.assemble_scalar(fem.form(one * dx(i + 1))), op=MPI.SUM)
            mass = comm.allreduce(fem.assemble_scalar(fem.form(density * dx(i + 1))), op=MPI.SUM)
            cells = comm.allreduce(int((self.index[:self.n_owned] == i).sum()), op=MPI.SUM)
            out.append({"name": m.name, "cells": cells, "volume": vol, "mass": mass})
        return out

    def material_at(self, cell: int) -> str:
        """The name of the material of a local cell."""
        return self.materials[int(self.index[cell])].name
