# certified Jacobian tests
curvefem_add_gtest(NAME test_jacobian_certificate LABEL unit
  SOURCES test_jacobian_certificate.cpp
  LIBS curvefem_jacobian)

# The committed Bernstein tables must equal a fresh run of their generator.
if(EXISTS /usr/bin/python3)
  add_test(NAME gen_bernstein_tables_check
    COMMAND /usr/bin/python3 ${PROJECT_SOURCE_DIR}/tools/gen_bernstein_tables.py --check)
  set_tests_properties(gen_bernstein_tables_check PROPERTIES LABELS unit)
else()
  message(STATUS "/usr/bin/python3 not found: gen_bernstein_tables_check is not registered")
endif()
