#include "meshing/io/gmsh_session.hpp"

#include <gmsh.h>

#include <mutex>

#include "meshing/core/log.hpp"

namespace curvefem::io {
namespace {
std::recursive_mutex g_gmsh_mutex;
bool g_initialized = false;
}  // namespace

struct GmshSession::Impl {
  std::unique_lock<std::recursive_mutex> lock{g_gmsh_mutex};
  Mode mode = Mode::new_model;
};

GmshSession::GmshSession(const std::string& model_name, Mode mode)
    : m_impl(std::make_unique<Impl>()) {
  m_impl->mode = mode;
  if (!g_initialized) {
    gmsh::initialize(0, nullptr, false);
    g_initialized = true;
  }
  gmsh::option::setNumber("General.Terminal", log::enabled(log::Level::debug) ? 1 : 0);
  gmsh::option::setNumber("General.Verbosity", log::enabled(log::Level::debug) ? 5 : 1);
  if (mode == Mode::keep_model) return;
  gmsh::clear();
  gmsh::model::add(model_name);
}

GmshSession::~GmshSession() {
  if (m_impl->mode == Mode::keep_model) return;
  try {
    gmsh::clear();
  } catch (...) {
  }
}

}  // namespace curvefem::io
