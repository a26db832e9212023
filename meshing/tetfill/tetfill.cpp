// fill_interior: input checks, gmsh 3D Delaunay on a discrete (not remeshed) surface, read-back
// with node tags mapped to input rows, and the independent verification before returning.
#include "meshing/tetfill/tetfill.hpp"

#include <gmsh.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/core/timer.hpp"
#include "meshing/io/gmsh_session.hpp"
#include "meshing/tetfill/isolated.hpp"

namespace curvefem::meshing::tetfill {
namespace {

constexpr int k_gmsh_triangle = 2;  // MSH element types
constexpr int k_gmsh_tet = 4;

// ---- input checks --------------------------------------------------------------------------

struct SurfaceInfo {
  std::vector<char> used;      ///< per vertex: referenced by a face
  std::vector<int> component;  ///< per face: its edge-connected component
  std::vector<double> volume;  ///< per component: signed enclosed volume × 6
  std::vector<int> container;  ///< per component: for a cavity (volume < 0), its solid
};

int find_root(std::vector<int>& parent, int x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}

/// Generalized winding number of the component `c` at p (1 inside, 0 outside), from the solid
/// angles of its triangles (Van Oosterom–Strackee).
double winding_number(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                      const std::vector<int>& component, int c, const Eigen::RowVector3d& p) {
  double sum = 0;
  for (long long f = 0; f < F.rows(); ++f) {
    if (component[f] != c) continue;
    const Eigen::RowVector3d a = V.row(F(f, 0)) - p, b = V.row(F(f, 1)) - p, d = V.row(F(f, 2)) - p;
    const double la = a.norm(), lb = b.norm(), ld = d.norm();
    sum += 2 * std::atan2(a.dot(b.cross(d)),
                          la * lb * ld + a.dot(b) * ld + b.dot(d) * la + d.dot(a) * lb);
  }
  return sum / (4 * M_PI);
}

/// Throws InputError unless (V, F) is a closed, edge-manifold, consistently oriented surface with
/// positive enclosed volume, and every inward component (a cavity) lies inside an outward one.
SurfaceInfo check_input(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F) {
  if (V.cols() != 3) throw InputError("tetfill: V must be #V x 3");
  if (F.cols() != 3) throw InputError("tetfill: F must be #F x 3");
  if (F.rows() < 4) throw InputError("tetfill: a closed surface needs at least 4 triangles");
  const long long n = V.rows();
  for (long long i = 0; i < n; ++i) {
    if (!V.row(i).allFinite()) {
      throw InputError("tetfill: non-finite vertex coordinate", {.vertex = i});
    }
  }
  std::vector<char> used(n, 0);
  // Directed edge (a, b) → face; every directed edge must be unique and have its reverse.
  std::unordered_map<long long, long long> directed;
  directed.reserve(3 * F.rows());
  auto key = [n](long long a, long long b) { return a * n + b; };
  for (long long f = 0; f < F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const long long a = F(f, k);
      if (a < 0 || a >= n) {
        throw InputError("tetfill: vertex index " + std::to_string(a) + " out of range",
                         {.face = f});
      }
      used[a] = 1;
    }
    if (F(f, 0) == F(f, 1) || F(f, 1) == F(f, 2) || F(f, 2) == F(f, 0)) {
      throw InputError("tetfill: degenerate face (repeated vertex index)", {.face = f});
    }
    for (int k = 0; k < 3; ++k) {
      const long long a = F(f, k), b = F(f, (k + 1) % 3);
      const auto [it, inserted] = directed.emplace(key(a, b), f);
      if (!inserted) {
        throw InputError("tetfill: edge " + std::to_string(a) + "-" + std::to_string(b) +
                             " is used twice in the same direction (faces " +
                             std::to_string(it->second) + " and " + std::to_string(f) +
                             "): inconsistently oriented face or non-manifold edge",
                         {.face = f});
      }
    }
  }
  // Closed: every directed edge has its reverse; faces across an edge share a component.
  std::vector<int> parent(F.rows());
  for (int f = 0; f < F.rows(); ++f) parent[f] = f;
  for (const auto& [k, f] : directed) {
    const long long a = k / n, b = k % n;
    const auto twin = directed.find(key(b, a));
    if (twin == directed.end()) {
      throw InputError(
          "tetfill: surface is open: boundary edge " + std::to_string(a) + "-" + std::to_string(b),
          {.face = f});
    }
    parent[find_root(parent, static_cast<int>(f))] =
        find_root(parent, static_cast<int>(twin->second));
  }
  SurfaceInfo info;
  info.used = std::move(used);
  info.component.assign(F.rows(), -1);
  std::vector<int> id_of_root(F.rows(), -1);
  int components = 0;
  for (int f = 0; f < F.rows(); ++f) {
    const int r = find_root(parent, f);
    if (id_of_root[r] < 0) id_of_root[r] = components++;
    info.component[f] = id_of_root[r];
  }
  // Signed volumes (cones from the centroid): the total must be positive (outward surface).
  const Eigen::RowVector3d c = V.colwise().mean();
  info.volume.assign(components, 0.0);
  std::vector<long long> first_face(components, -1);
  for (long long f = 0; f < F.rows(); ++f) {
    const Eigen::RowVector3d a = V.row(F(f, 0)) - c, b = V.row(F(f, 1)) - c, d = V.row(F(f, 2)) - c;
    info.volume[info.component[f]] += a.dot(b.cross(d));
    if (first_face[info.component[f]] < 0) first_face[info.component[f]] = f;
  }
  double total = 0;
  for (const double v : info.volume) total += v;
  if (!(total > 0)) {
    throw InputError("tetfill: enclosed volume " + std::to_string(total / 6) +
                     " is not positive: the surface must be oriented outward");
  }
  // Nesting: at a point of component h, the other components must have winding number 0 if h
  // is outward (a solid's outer shell) and 1 if h is inward (a cavity, inside a solid). A cavity
  // goes to the smallest outward component containing it. Only components whose bounding box
  // holds the point can have a non-zero winding number there.
  std::vector<Eigen::RowVector3d> lo(components, Eigen::RowVector3d::Constant(INFINITY)),
      hi(components, Eigen::RowVector3d::Constant(-INFINITY));
  for (long long f = 0; f < F.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      lo[info.component[f]] = lo[info.component[f]].cwiseMin(V.row(F(f, k)));
      hi[info.component[f]] = hi[info.component[f]].cwiseMax(V.row(F(f, k)));
    }
  }
  info.container.assign(components, -1);
  for (int h = 0; h < components && components > 1; ++h) {
    const long long f = first_face[h];
    const Eigen::RowVector3d p = (V.row(F(f, 0)) + V.row(F(f, 1)) + V.row(F(f, 2))) / 3;
    long long total = 0;
    for (int o = 0; o < components; ++o) {
      if (o == h || (p.array() < lo[o].array()).any() || (p.array() > hi[o].array()).any())
        continue;
      const long long w = std::llround(winding_number(V, F, info.component, o, p));
      total += w;
      if (w == 1 && info.volume[h] < 0 && info.volume[o] > 0 &&
          (info.container[h] < 0 || info.volume[o] < info.volume[info.container[h]]))
        info.container[h] = o;
    }
    const long long expected = info.volume[h] > 0 ? 0 : 1;
    if (total != expected) {
      throw InputError("tetfill: " + std::string(info.volume[h] > 0 ? "outward" : "inward") +
                           " component " + std::to_string(h) + " is nested with winding number " +
                           std::to_string(total) + " (expected " + std::to_string(expected) +
                           "): nested shells must alternate outward/inward (cavities inward)",
                       {.face = f});
    }
  }
  if (components == 1 && info.volume[0] <= 0) info.container[0] = -1;
  return info;
}

// ---- interior size field (size_factor != 1) -----------------------------------------------

/// size(x) = factor × mean length of the edges at the boundary vertex nearest to x, found in a
/// uniform grid by growing rings of cells.
class BoundarySizeField {
 public:
  BoundarySizeField(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                    const std::vector<char>& used, double factor)
      : m_factor(factor) {
    const long long n = V.rows();
    std::vector<double> sum(n, 0.0);
    std::vector<int> count(n, 0);
    for (long long f = 0; f < F.rows(); ++f) {
      for (int k = 0; k < 3; ++k) {
        const int a = F(f, k), b = F(f, (k + 1) % 3);
        const double l = (V.row(a) - V.row(b)).norm();
        sum[a] += l, sum[b] += l, ++count[a], ++count[b];
      }
    }
    for (long long i = 0; i < n; ++i) {
      if (!used[i]) continue;
      m_points.push_back(V.row(i).transpose());
      m_sizes.push_back(sum[i] / count[i]);
    }
    m_lo = m_points[0], m_hi = m_points[0];
    for (const auto& p : m_points) m_lo = m_lo.cwiseMin(p), m_hi = m_hi.cwiseMax(p);
    const double extent = std::max((m_hi - m_lo).maxCoeff(), 1e-300);
    m_res = std::clamp(static_cast<int>(std::cbrt(m_points.size() / 2.0)), 1, 256);
    m_cell = extent / m_res;
    m_cells.assign(static_cast<size_t>(m_res) * m_res * m_res, {});
    for (size_t i = 0; i < m_points.size(); ++i)
      m_cells[cell_index(cell_of(m_points[i]))].push_back(i);
  }

  double operator()(double x, double y, double z) const {
    const Eigen::Vector3d p(x, y, z);
    const std::array<int, 3> c = cell_of(p);
    double best = INFINITY;
    size_t best_i = 0;
    for (int r = 0; r <= m_res; ++r) {
      // Points in ring r + 1 are at least r × cell away: stop once the best is closer.
      if (best < (r - 1) * m_cell) break;
      for (int i = c[0] - r; i <= c[0] + r; ++i) {
        for (int j = c[1] - r; j <= c[1] + r; ++j) {
          for (int k = c[2] - r; k <= c[2] + r; ++k) {
            if (std::max({std::abs(i - c[0]), std::abs(j - c[1]), std::abs(k - c[2])}) != r)
              continue;
            if (i < 0 || j < 0 || k < 0 || i >= m_res || j >= m_res || k >= m_res) continue;
            for (const size_t q : m_cells[cell_index({i, j, k})]) {
              const double d = (m_points[q] - p).squaredNorm();
              if (d < best * best || best == INFINITY) best = std::sqrt(d), best_i = q;
            }
          }
        }
      }
    }
    return m_factor * m_sizes[best_i];
  }

 private:
  std::array<int, 3> cell_of(const Eigen::Vector3d& p) const {
    std::array<int, 3> c;
    for (int d = 0; d < 3; ++d) {
      c[d] = std::clamp(static_cast<int>(std::floor((p[d] - m_lo[d]) / m_cell)), 0, m_res - 1);
    }
    return c;
  }
  size_t cell_index(const std::array<int, 3>& c) const {
    return (static_cast<size_t>(c[0]) * m_res + c[1]) * m_res + c[2];
  }

  double m_factor;
  std::vector<Eigen::Vector3d> m_points;
  std::vector<double> m_sizes;
  Eigen::Vector3d m_lo, m_hi;
  int m_res = 1;
  double m_cell = 1;
  std::vector<std::vector<size_t>> m_cells;
};

// ---- gmsh state -----------------------------------------------------------------------------

/// Sets gmsh options for this call and restores the previous values (gmsh options are global and
/// outlive the session's model); also owns the size callback and the gmsh logger.
class GmshSettings {
 public:
  void set(const std::string& name, double value) {
    double old = 0;
    gmsh::option::getNumber(name, old);
    m_saved.emplace_back(name, old);
    gmsh::option::setNumber(name, value);
  }
  void set_size_callback(std::function<double(int, int, double, double, double)> f) {
    gmsh::model::mesh::setSizeCallback(std::move(f));
    m_callback = true;
  }
  /// Gmsh's messages of this call (collected instead of printed).
  std::vector<std::string> messages() const {
    std::vector<std::string> lines;
    gmsh::logger::get(lines);
    return lines;
  }
  GmshSettings() { gmsh::logger::start(); }
  ~GmshSettings() {
    try {
      if (m_callback) gmsh::model::mesh::removeSizeCallback();
      for (auto it = m_saved.rbegin(); it != m_saved.rend(); ++it) {
        gmsh::option::setNumber(it->first, it->second);
      }
      std::vector<std::string> lines;
      gmsh::logger::get(lines);
      for (const auto& l : lines) log::debug("gmsh: ", l);
      gmsh::logger::stop();
    } catch (...) {
    }
  }
  GmshSettings(const GmshSettings&) = delete;
  GmshSettings& operator=(const GmshSettings&) = delete;

 private:
  std::vector<std::pair<std::string, double>> m_saved;
  bool m_callback = false;
};

/// The error lines of gmsh's messages (without the "Error: " prefix and the summary block), plus
/// `what` (the text of a gmsh exception) if not empty.
std::vector<std::string> gmsh_errors(const std::vector<std::string>& messages,
                                     const std::string& what) {
  std::vector<std::string> errors;
  if (!what.empty()) errors.push_back(what);
  for (const auto& m : messages) {
    if (m.rfind("Error", 0) != 0) continue;
    const std::size_t start = m.find_first_not_of(": ", 5);
    if (start == std::string::npos) continue;
    const std::string text = m.substr(start);
    const bool summary = text[0] == '-' || text.rfind("Mesh generation error summary", 0) == 0 ||
                         text.rfind("Check the full log", 0) == 0 || std::isdigit(text[0]);
    const bool known = std::any_of(errors.begin(), errors.end(), [&](const std::string& e) {
      return e.find(text) != std::string::npos || text.find(e) != std::string::npos;
    });
    if (!summary && !known) errors.push_back(text);
  }
  return errors;
}

/// MeshingError "tetfill: <stage> failed: <errors>"; the stage comes from the error texts
/// (gmsh's boundary recovery is tetgen's: "PLC", "recover", "Steiner", "missing", "boundary").
[[noreturn]] void throw_gmsh_failure(const std::vector<std::string>& errors) {
  std::string all;
  for (const auto& e : errors) all += (all.empty() ? "" : "; ") + e;
  std::string lower = all;
  for (auto& ch : lower) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  bool recovery = false;
  for (const char* word : {"recover", "plc", "steiner", "missing", "boundary"}) {
    recovery = recovery || lower.find(word) != std::string::npos;
  }
  throw MeshingError(std::string("tetfill: ") + (recovery ? "boundary recovery" : "3D meshing") +
                     " failed: " + (all.empty() ? "unknown gmsh error" : all));
}

/// What fill_interior reads back from gmsh.
struct GmshOutput {
  std::vector<std::size_t> tet_tags, tet_nodes, all_tags, surface_tags, tri_tags, tri_back;
  std::vector<double> all_coords;
  double seconds = 0;
};

void append_bytes(std::string& buf, const void* p, std::size_t n) {
  buf.append(static_cast<const char*>(p), n);
}
template <class T>
void append_vector(std::string& buf, const std::vector<T>& v) {
  const std::uint64_t n = v.size();
  append_bytes(buf, &n, sizeof n);
  append_bytes(buf, v.data(), n * sizeof(T));
}
template <class T>
bool read_vector(const std::string& buf, std::size_t& at, std::vector<T>& v) {
  std::uint64_t n = 0;
  if (at + sizeof n > buf.size()) return false;
  std::memcpy(&n, buf.data() + at, sizeof n);
  at += sizeof n;
  if (n > (buf.size() - at) / sizeof(T)) return false;
  v.resize(n);
  std::memcpy(v.data(), buf.data() + at, n * sizeof(T));
  at += n * sizeof(T);
  return true;
}

/// Runs `body` through detail::run_isolated (gmsh in a forked child), with GmshOutput
/// serialized as its payload. Errors as detail::run_isolated; a payload that does not decode
/// exactly throws MeshingError.
GmshOutput run_gmsh_isolated(const std::function<void(GmshOutput&)>& body) {
  const std::string buf = detail::run_isolated(
      [&body] {
        GmshOutput out;
        body(out);
        std::string bytes;
        for (const auto* v : {&out.tet_tags, &out.tet_nodes, &out.all_tags, &out.surface_tags,
                              &out.tri_tags, &out.tri_back})
          append_vector(bytes, *v);
        append_vector(bytes, out.all_coords);
        append_bytes(bytes, &out.seconds, sizeof out.seconds);
        return bytes;
      },
      {.failed = "tetfill: 3D meshing failed: ",
       .name = "gmsh",
       .note = "; gmsh 4.8's boundary recovery aborts on some near-degenerate surfaces"});
  GmshOutput out;
  std::size_t at = 0;
  bool ok = true;
  for (auto* v : {&out.tet_tags, &out.tet_nodes, &out.all_tags, &out.surface_tags, &out.tri_tags,
                  &out.tri_back})
    ok = ok && read_vector(buf, at, *v);
  ok = ok && read_vector(buf, at, out.all_coords) && at + sizeof out.seconds == buf.size();
  if (!ok) throw MeshingError("tetfill: 3D meshing failed: truncated output from the gmsh child");
  std::memcpy(&out.seconds, buf.data() + at, sizeof out.seconds);
  return out;
}

}  // namespace

namespace detail {

std::string run_isolated(const std::function<std::string()>& body, const IsolationText& text) {
  int fds[2];
  if (::pipe(fds) != 0)
    throw MeshingError(text.failed + "cannot create a pipe: " + std::strerror(errno));
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    throw MeshingError(text.failed + "cannot fork: " + std::strerror(errno));
  }
  if (pid == 0) {  // child: run, report, leave without running the parent's destructors
    ::close(fds[0]);
    char tag = '\0';
    std::string buf;
    try {
      buf = body();
    } catch (const std::exception& e) {
      tag = '\1', buf = e.what();
    } catch (...) {
      tag = '\1', buf = text.failed + "unknown error in " + text.name;
    }
    auto write_all = [&](const char* p, std::size_t n) {
      std::size_t done = 0;
      while (done < n) {
        const ssize_t w = ::write(fds[1], p + done, n - done);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) ::_exit(3);
        done += std::size_t(w);
      }
    };
    write_all(&tag, 1);
    write_all(buf.data(), buf.size());
    ::close(fds[1]);
    ::_exit(0);
  }
  // Parent: read to the end before waiting, else a payload larger than the pipe buffer would
  // block the child's write while we block in waitpid.
  ::close(fds[1]);
  std::string buf;
  char chunk[1 << 16];
  for (;;) {
    const ssize_t r = ::read(fds[0], chunk, sizeof chunk);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) break;
    buf.append(chunk, std::size_t(r));
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFSIGNALED(status))
    throw MeshingError(text.failed + text.name + " crashed (signal " +
                       std::to_string(WTERMSIG(status)) + " " + strsignal(WTERMSIG(status)) +
                       text.note + ")");
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || buf.empty())
    throw MeshingError(text.failed + "the " + text.name + " child process exited with status " +
                       std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1));
  if (buf[0] == '\1') throw MeshingError(buf.substr(1));
  buf.erase(0, 1);
  return buf;
}

}  // namespace detail

TetFillResult fill_interior(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                            const TetFillOptions& options) {
  Stopwatch watch;
  if (!(options.size_factor > 0) || !std::isfinite(options.size_factor)) {
    throw InputError("tetfill: size_factor must be positive");
  }
  const SurfaceInfo info = check_input(V, F);
  const std::vector<char>& used = info.used;
  const long long n = V.rows();
  const int components = static_cast<int>(info.volume.size());

  // One discrete surface per component (tag c + 1), holding the nodes it uses first.
  std::vector<std::vector<std::size_t>> node_tags(components), tri_nodes(components);
  std::vector<std::vector<double>> coords(components);
  std::vector<char> assigned(n, 0);
  std::size_t referenced = 0;
  for (long long f = 0; f < F.rows(); ++f) {
    const int c = info.component[f];
    for (int k = 0; k < 3; ++k) {
      const int i = F(f, k);
      tri_nodes[c].push_back(static_cast<std::size_t>(i) + 1);
      if (assigned[i]) continue;
      assigned[i] = 1, ++referenced;
      node_tags[c].push_back(static_cast<std::size_t>(i) + 1);
      coords[c].insert(coords[c].end(), {V(i, 0), V(i, 1), V(i, 2)});
    }
  }
  std::unique_ptr<BoundarySizeField> size_field;
  if (options.size_factor != 1.0) {
    size_field = std::make_unique<BoundarySizeField>(V, F, used, options.size_factor);
  }

  TetFillResult result;
  result.boundary_vertices = static_cast<int>(n);
  auto run_gmsh = [&](GmshOutput& out, int threads) {
    io::GmshSession session("tetfill");
    GmshSettings settings;
    // Library use: gmsh never prints (its messages go to the debug log).
    gmsh::option::setNumber("General.Terminal", 0);
    settings.set("General.NumThreads", std::max(1, threads));
    settings.set("Mesh.Algorithm3D", 1);  // Delaunay with tetgen-style boundary recovery
    settings.set("Mesh.Optimize", options.optimize ? 1 : 0);
    settings.set("Mesh.OptimizeNetgen", 0);
    settings.set("Mesh.Renumber", 0);  // keep node tag i + 1 = input row i
    // No exception from inside gmsh's mesher: it would leave gmsh's global "busy" lock set and
    // every later generate() in the process would silently do nothing. Errors are read from the
    // log instead.
    settings.set("General.AbortOnError", 0);
    settings.set("Mesh.MeshSizeExtendFromBoundary", size_field ? 0 : 1);
    if (size_field) {
      const BoundarySizeField* field = size_field.get();
      settings.set_size_callback(
          [field](int, int, double x, double y, double z) { return (*field)(x, y, z); });
    }
    Stopwatch gmsh_watch;
    std::vector<double> surface_coords, param;
    try {
      for (int c = 0; c < components; ++c) {
        gmsh::model::addDiscreteEntity(2, c + 1);
        gmsh::model::mesh::addNodes(2, c + 1, node_tags[c], coords[c]);
        gmsh::model::mesh::addElementsByType(c + 1, k_gmsh_triangle, {}, tri_nodes[c]);
      }
      // A volume per outward component: its surface loop first, then its cavities' loops.
      for (int o = 0; o < components; ++o) {
        if (info.volume[o] <= 0) continue;
        std::vector<int> loops = {gmsh::model::geo::addSurfaceLoop({o + 1})};
        for (int h = 0; h < components; ++h) {
          if (info.container[h] == o) loops.push_back(gmsh::model::geo::addSurfaceLoop({h + 1}));
        }
        gmsh::model::geo::addVolume(loops);
      }
      gmsh::model::geo::synchronize();
      gmsh::model::mesh::generate(3);
      gmsh::model::mesh::getElementsByType(k_gmsh_tet, out.tet_tags, out.tet_nodes);
      gmsh::model::mesh::getNodes(out.all_tags, out.all_coords, param, -1, -1, false, false);
      gmsh::model::mesh::getNodes(out.surface_tags, surface_coords, param, 2, -1, false, false);
      gmsh::model::mesh::getElementsByType(k_gmsh_triangle, out.tri_tags, out.tri_back);
    } catch (const std::string& what) {  // gmsh 4.8's API throws its message as a string
      throw_gmsh_failure(gmsh_errors(settings.messages(), what));
    } catch (const std::exception& e) {
      throw_gmsh_failure(gmsh_errors(settings.messages(), e.what()));
    }
    // With AbortOnError = 0, meshing errors are only logged.
    const std::vector<std::string> errors = gmsh_errors(settings.messages(), "");
    if (!errors.empty()) throw_gmsh_failure(errors);
    out.seconds = gmsh_watch.seconds();
  };
  GmshOutput g;
  if (options.isolate)
    g = run_gmsh_isolated([&](GmshOutput& out) { run_gmsh(out, 1); });
  else
    run_gmsh(g, options.threads);
  result.gmsh_seconds = g.seconds;
  const std::vector<std::size_t>&tet_nodes = g.tet_nodes, &all_tags = g.all_tags,
        &surface_tags = g.surface_tags, &tri_back = g.tri_back;
  const std::vector<double>& all_coords = g.all_coords;

  // The surface must come back untouched: same nodes, same triangles.
  if (surface_tags.size() != referenced ||
      tri_back.size() != 3 * static_cast<std::size_t>(F.rows())) {
    throw MeshingError("tetfill: boundary recovery failed: gmsh changed the surface mesh (" +
                       std::to_string(surface_tags.size()) + " surface nodes for " +
                       std::to_string(referenced) + ", " + std::to_string(tri_back.size() / 3) +
                       " triangles for " + std::to_string(F.rows()) +
                       "): Steiner points on the boundary");
  }
  if (g.tet_tags.empty()) throw MeshingError("tetfill: 3D meshing failed: gmsh produced no tets");

  // Node tags → rows: tag i + 1 is input row i (bit-identical); interior nodes are appended in
  // order of first use by a tet.
  std::size_t max_tag = 0;
  for (const auto t : all_tags) max_tag = std::max(max_tag, t);
  std::vector<long long> node_of(max_tag + 1, -1);
  for (std::size_t k = 0; k < all_tags.size(); ++k)
    node_of[all_tags[k]] = static_cast<long long>(k);
  std::vector<int> row_of(max_tag + 1, -1);
  std::vector<std::size_t> interior;
  for (const auto t : tet_nodes) {
    if (t == 0 || t > max_tag || node_of[t] < 0) {
      throw MeshingError("tetfill: read-back failed: tet uses unknown gmsh node " +
                         std::to_string(t));
    }
    if (row_of[t] >= 0) continue;
    if (t <= static_cast<std::size_t>(n)) {
      if (!used[t - 1]) throw MeshingError("tetfill: read-back failed: unreferenced node used");
      row_of[t] = static_cast<int>(t - 1);
    } else {
      row_of[t] = static_cast<int>(n + interior.size());
      interior.push_back(t);
    }
  }
  result.V.resize(n + static_cast<long long>(interior.size()), 3);
  result.V.topRows(n) = V;
  for (std::size_t k = 0; k < interior.size(); ++k) {
    const long long j = node_of[interior[k]];
    result.V.row(n + k) << all_coords[3 * j], all_coords[3 * j + 1], all_coords[3 * j + 2];
  }
  for (long long i = 0; i < n; ++i) {
    if (!used[i]) continue;
    const long long j = node_of[i + 1];
    if (j < 0 || all_coords[3 * j] != V(i, 0) || all_coords[3 * j + 1] != V(i, 1) ||
        all_coords[3 * j + 2] != V(i, 2)) {
      throw MeshingError(
          "tetfill: read-back failed: the gmsh node of an input vertex has other coordinates",
          {.vertex = i});
    }
  }
  // Gmsh's tets are positively oriented (det(x1 - x0, x2 - x0, x3 - x0) > 0), as verified below.
  result.T.resize(static_cast<long long>(g.tet_tags.size()), 4);
  for (std::size_t e = 0; e < g.tet_tags.size(); ++e) {
    for (int k = 0; k < 4; ++k) result.T(e, k) = row_of[tet_nodes[4 * e + k]];
  }

  const TetFillVerification check = verify_tetfill(V, F, result);
  if (!check.valid()) {
    throw MeshingError(log::cat("tetfill: verification failed: ", check.non_positive_tets,
                                " non-positive tets, ", check.missing_boundary_faces,
                                " missing and ", check.extra_boundary_faces,
                                " extra boundary faces, ", check.bad_interior_faces,
                                " bad interior faces, ", check.moved_boundary_vertices,
                                " moved boundary vertices, volume error ", check.volume_error_rel));
  }
  result.seconds = watch.seconds();
  const std::string summary = log::cat(
      "tetfill: ", F.rows(), " boundary faces -> ", result.T.rows(), " tets, ", interior.size(),
      " interior vertices in ", result.seconds, " s (gmsh ", result.gmsh_seconds, " s)");
  if (options.quiet)
    log::debug(summary);
  else
    log::info(summary);
  return result;
}

}  // namespace curvefem::meshing::tetfill
