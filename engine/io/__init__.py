"""File formats at the engine's edge: STL meshes in, VTK (ParaView) out. No I/O inside kernels."""
from .stl import StlError, plate, read_stl, triangle_normals, write_stl  # noqa: F401
from .vtk import write_packing_vtp, write_particles_vtp, write_pvd, write_walls_vtp  # noqa: F401
