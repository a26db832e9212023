#include "meshing/core/error.hpp"

#include <sstream>

namespace curvefem {

std::string ErrorContext::location_prefix() const {
  if (file.empty() && line < 0 && byte_offset < 0) return {};
  std::ostringstream s;
  if (!file.empty()) s << file;
  if (line >= 0) s << (file.empty() ? "line " : ":") << line;
  if (byte_offset >= 0) s << (file.empty() ? "" : ": ") << "byte " << byte_offset;
  s << ": ";
  return s.str();
}

std::string ErrorContext::id_suffix() const {
  std::ostringstream s;
  const char* sep = " (";
  auto add = [&](const char* name, long long id) {
    if (id < 0) return;
    s << sep << name << ' ' << id;
    sep = ", ";
  };
  add("vertex", vertex);
  add("face", face);
  add("element", element);
  if (std::string(sep) == ", ") s << ')';
  return s.str();
}

Error::Error(const std::string& what, ErrorContext context)
    : std::runtime_error(context.location_prefix() + what + context.id_suffix()),
      m_context(std::move(context)),
      m_defect(what) {}

namespace detail {
void verify_failed(const char* cond, const std::string& msg, const char* file, int line) {
  std::ostringstream s;
  s << "internal check `" << cond << "` failed at " << file << ':' << line << ": " << msg;
  throw Error(s.str());
}
}  // namespace detail

}  // namespace curvefem
