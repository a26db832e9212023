#include "tools/curvefem/commands.hpp"
namespace curvefem::cli { void register_demo(CLI::App&) {} }
