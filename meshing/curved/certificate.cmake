# Certified positivity of det J for Lagrange tets of order 1..4 (Eigen only).
# Tables: generated/bernstein_tables.inc, written by tools/gen_bernstein_tables.py.
add_library(curvefem_jacobian STATIC jacobian_certificate.cpp)
target_include_directories(curvefem_jacobian PUBLIC ${PROJECT_SOURCE_DIR})
target_link_libraries(curvefem_jacobian PUBLIC curvefem_core)
