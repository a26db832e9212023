# VTU / MSH volume tests
curvefem_add_gtest(NAME test_vtu_io LABEL unit
  SOURCES test_vtu_io.cpp
  LIBS curvefem_io VTK::CommonCore VTK::CommonDataModel VTK::IOXML)
curvefem_add_gtest(NAME test_msh_io LABEL unit
  SOURCES test_msh_io.cpp
  LIBS curvefem_io Gmsh::Gmsh)
