# basis and quadrature tests
curvefem_add_gtest(NAME test_fem_basis LABEL unit
  SOURCES test_lagrange_basis.cpp test_quadrature.cpp
  LIBS curvefem_fem)

# The committed generated tables must equal a fresh run of their generator.
if(EXISTS /usr/bin/python3)
  add_test(NAME gen_lagrange_basis_check
    COMMAND /usr/bin/python3 ${PROJECT_SOURCE_DIR}/tools/gen_lagrange_basis.py --check)
  set_tests_properties(gen_lagrange_basis_check PROPERTIES LABELS unit)
  # The symmetric quadrature rules are found by a minutes-long search: re-verify them exactly
  # (positive weights, interior points, every monomial up to the degree) instead of regenerating.
  add_test(NAME gen_symmetric_quadrature_verify
    COMMAND /usr/bin/python3 ${PROJECT_SOURCE_DIR}/tools/gen_symmetric_quadrature.py --verify)
  set_tests_properties(gen_symmetric_quadrature_verify PROPERTIES LABELS unit)
else()
  message(STATUS "/usr/bin/python3 not found: the generated-table checks are not registered")
endif()
