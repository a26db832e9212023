# target_sources(curvefem_io PRIVATE ...) for surface readers/writers
