# Surface readers/writers (OBJ, OFF, STL, PLY, MSH) and the MSH parser shared with the volume reader.
target_sources(curvefem_io PRIVATE
  msh_parser.cpp
  surface_io.cpp
  surface_msh.cpp
  surface_obj.cpp
  surface_off.cpp
  surface_ply.cpp
  surface_stl.cpp
  text_scanner.cpp
)
