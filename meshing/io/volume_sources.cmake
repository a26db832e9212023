# target_sources(curvefem_io PRIVATE ...) for VTU / MSH volume I/O
target_sources(curvefem_io PRIVATE
  msh_io.cpp
  node_permutation.cpp
  vtu_binary_check.cpp
  vtu_io.cpp
)
# zlib (already a dependency of VTK's XML I/O) decodes compressed cell offsets in the VTU check.
find_package(ZLIB REQUIRED)
target_link_libraries(curvefem_io PRIVATE ZLIB::ZLIB)
