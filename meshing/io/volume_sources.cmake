# target_sources(curvefem_io PRIVATE ...) for VTU / MSH volume I/O
