"""Meshes: one loader for the built-in box, gmsh-generated solids and mesh files, and what it is made of.

    loader.py       load_mesh (the one mesh loader): MeshArrays and their cell checks, gmsh solids, mesh
                    files, distribution to a LoadedMesh, bounding_box and mesh_size
    surfaces.py     closed STL/OBJ/PLY/OFF surfaces: read, checked closed, tetrahedralised by gmsh
    groups.py       gmsh physical groups of every dimension (volumes, curves, points)
    prisms.py       prism (wedge) meshes through dolfinx's C++ layer
    resources.py    memory estimate before allocation (a mesh that cannot fit is refused)
    occ_parts.py    a solid built with gmsh's OpenCASCADE kernel, meshed to .msh (demos, benchmarks, scripts)
"""
from fem_forms.meshes.loader import (LoadedMesh, MeshArrays, bounding_box, check_cells, from_arrays, load_mesh,
                                    mesh_size)

__all__ = ["LoadedMesh", "MeshArrays", "bounding_box", "check_cells", "from_arrays", "load_mesh", "mesh_size"]
