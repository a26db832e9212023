#include "meshing/io/pvd.hpp"

#include <sstream>

#include "meshing/core/atomic_file.hpp"

namespace curvefem::io {
namespace {
std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}
}  // namespace

void write_pvd(const std::filesystem::path& path, const std::vector<PvdEntry>& entries) {
  std::ostringstream s;
  s << "<?xml version=\"1.0\"?>\n"
    << "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
    << "  <Collection>\n";
  for (const auto& e : entries) {
    s << "    <DataSet timestep=\"" << e.timestep << "\" part=\"" << e.part << "\" file=\""
      << xml_escape(e.file) << "\"";
    if (!e.name.empty()) s << " name=\"" << xml_escape(e.name) << "\"";
    s << "/>\n";
  }
  s << "  </Collection>\n</VTKFile>\n";
  write_text_file_atomic(path, s.str());
}

}  // namespace curvefem::io
