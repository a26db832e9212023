# Certified positivity of det J for Lagrange tets of order 1..4 (Eigen only).
# Tables: generated/bernstein_tables.inc, written by tools/gen_bernstein_tables.py: the exact
# Lagrange-to-Bernstein tables (Jacobian degrees 3, 6, 9) and the gradient bounds Λ of the affine
# path (orders 1..4). tests/meshing/curved/certificate_tests.cmake registers
# gen_bernstein_tables_check, which regenerates the file and fails when the committed copy differs.
add_library(curvefem_jacobian STATIC jacobian_certificate.cpp element_distortion.cpp)
target_include_directories(curvefem_jacobian PUBLIC ${PROJECT_SOURCE_DIR})
target_link_libraries(curvefem_jacobian PUBLIC curvefem_core)
