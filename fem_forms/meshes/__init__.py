"""Meshes: one loader for the built-in box, gmsh-generated solids and mesh files, and what it is made of.

    loader.py       load_mesh (the one mesh loader), from_arrays, distribution to a LoadedMesh,
                    bounding_box and mesh_size
    arrays.py       MeshArrays (a volume mesh on rank 0), its cell checks and compaction
    gmsh_models.py  gmsh-generated solids (cylinder, sphere, revolve) and the arrays of a gmsh model
    files.py        mesh files: .msh, meshio volume meshes, closed surfaces filled with tetrahedra
    surfaces.py     closed STL/OBJ/PLY/OFF surfaces: read, checked closed, tetrahedralised by gmsh
    groups.py       gmsh physical groups of every dimension (volumes, curves, points)
    prisms.py       prism (wedge) meshes through dolfinx's C++ layer
    resources.py    memory estimate before allocation (a mesh that cannot fit is refused)
    occ_parts.py    a solid built with gmsh's OpenCASCADE kernel, meshed to .msh (demos, benchmarks, scripts)
"""
from fem_forms.meshes.arrays import MeshArrays, check_cells
from fem_forms.meshes.loader import LoadedMesh, bounding_box, from_arrays, load_mesh, mesh_size

__all__ = ["LoadedMesh", "MeshArrays", "bounding_box", "check_cells", "from_arrays", "load_mesh", "mesh_size"]
