#include "meshing/check/check_surface.hpp"
