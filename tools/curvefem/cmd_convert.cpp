#include "tools/curvefem/commands.hpp"
namespace curvefem::cli { void register_convert(CLI::App&) {} }
