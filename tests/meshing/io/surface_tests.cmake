# Surface reader/writer tests. test_surface_io.cpp builds two executables: the unit tests and, with
# CURVEFEM_SURFACE_IO_DATA, the tests on the real meshes of ../shared/data (label data).
curvefem_add_gtest(NAME test_surface_io LABEL unit
  SOURCES test_surface_io.cpp
  LIBS curvefem_io Gmsh::Gmsh)
curvefem_add_gtest(NAME test_surface_io_data LABEL data
  SOURCES test_surface_io.cpp
  LIBS curvefem_io)
target_compile_definitions(test_surface_io_data PRIVATE CURVEFEM_SURFACE_IO_DATA)
# Truncated / byte-flipped files: read or InputError, nothing else (run under CURVEFEM_SANITIZE too).
curvefem_add_gtest(NAME test_reader_garbage LABEL unit
  SOURCES test_reader_garbage.cpp
  LIBS curvefem_io Gmsh::Gmsh)
