# VTU / MSH volume tests
