#include "meshing/io/vtu_io.hpp"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkCommand.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkIdTypeArray.h>
#include <vtkIntArray.h>
#include <vtkLagrangeTetra.h>
#include <vtkLagrangeTriangle.h>
#include <vtkLogger.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkQuadraticTetra.h>
#include <vtkQuadraticTriangle.h>
#include <vtkTetra.h>
#include <vtkTriangle.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <map>
#include <mutex>
#include <optional>
#include <set>

#include "meshing/core/atomic_file.hpp"
#include "meshing/core/error.hpp"
#include "meshing/core/log.hpp"
#include "meshing/io/node_permutation.hpp"
#include "meshing/io/vtu_binary_check.hpp"

namespace curvefem::io {
namespace {

// The cell-data array that carries LagrangeMesh::cell_tags.
constexpr const char* k_tag_array = "tag";

// VTK stores some reference coordinates rounded (~1e-6); the lattice spacing is ≥ 1/4.
constexpr double k_match_tolerance = 1e-4;

const char* kind_name(CellKind kind) {
  return kind == CellKind::triangle ? "triangle" : "tetrahedron";
}

/// The cell type write_vtu uses for (kind, order).
int vtk_cell_type(CellKind kind, int order) {
  if (kind == CellKind::tetrahedron) return order == 1 ? VTK_TETRA : VTK_LAGRANGE_TETRAHEDRON;
  return order == 1 ? VTK_TRIANGLE : VTK_LAGRANGE_TRIANGLE;
}

struct CellShape {
  CellKind kind;
  int order;
};

/// (VTK cell type, point count) → kind and order; nullopt for anything read_vtu does not accept
/// (other types, or a Lagrange cell whose point count is no complete simplex of order 1..4).
std::optional<CellShape> classify(int type, vtkIdType points) {
  auto fixed = [&](CellKind kind, int order) -> std::optional<CellShape> {
    if (points != num_lagrange_nodes(kind, order)) return std::nullopt;
    return CellShape{kind, order};
  };
  auto lagrange = [&](CellKind kind) -> std::optional<CellShape> {
    const int order = order_from_node_count(kind, static_cast<int>(points));
    if (order < 1 || order > k_max_order) return std::nullopt;
    return CellShape{kind, order};
  };
  switch (type) {
    case VTK_TRIANGLE:
      return fixed(CellKind::triangle, 1);
    case VTK_TETRA:
      return fixed(CellKind::tetrahedron, 1);
    case VTK_QUADRATIC_TRIANGLE:
      return fixed(CellKind::triangle, 2);
    case VTK_QUADRATIC_TETRA:
      return fixed(CellKind::tetrahedron, 2);
    case VTK_LAGRANGE_TRIANGLE:
      return lagrange(CellKind::triangle);
    case VTK_LAGRANGE_TETRAHEDRON:
      return lagrange(CellKind::tetrahedron);
    default:
      return std::nullopt;
  }
}

/// VTK's own reference coordinates (n × 3) of a cell of `type` with n points.
Eigen::MatrixXd vtk_reference_coordinates(int type, int n) {
  vtkSmartPointer<vtkCell> cell;
  switch (type) {
    case VTK_TRIANGLE:
      cell = vtkSmartPointer<vtkTriangle>::New();
      break;
    case VTK_TETRA:
      cell = vtkSmartPointer<vtkTetra>::New();
      break;
    case VTK_QUADRATIC_TRIANGLE:
      cell = vtkSmartPointer<vtkQuadraticTriangle>::New();
      break;
    case VTK_QUADRATIC_TETRA:
      cell = vtkSmartPointer<vtkQuadraticTetra>::New();
      break;
    case VTK_LAGRANGE_TRIANGLE:
      cell = vtkSmartPointer<vtkLagrangeTriangle>::New();
      break;
    case VTK_LAGRANGE_TETRAHEDRON:
      cell = vtkSmartPointer<vtkLagrangeTetra>::New();
      break;
    default:
      CF_VERIFY(false, "no reference coordinates for VTK cell type " + std::to_string(type));
  }
  // Higher-order cells derive their order from the number of points.
  cell->GetPointIds()->SetNumberOfIds(n);
  cell->GetPoints()->SetNumberOfPoints(n);
  for (int i = 0; i < n; ++i) {
    cell->GetPointIds()->SetId(i, i);
    cell->GetPoints()->SetPoint(i, 0.0, 0.0, 0.0);
  }
  cell->Initialize();
  CF_VERIFY(cell->GetNumberOfPoints() == n, "VTK cell type " + std::to_string(type) + " has " +
                                                std::to_string(cell->GetNumberOfPoints()) +
                                                " points, expected " + std::to_string(n));
  const double* pcoords = cell->GetParametricCoords();
  CF_VERIFY(pcoords != nullptr,
            "VTK cell type " + std::to_string(type) + " has no parametric coordinates");
  Eigen::MatrixXd x(n, 3);
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) x(i, d) = pcoords[3 * i + d];
  return x;
}

/// Cached perm for a VTK cell type: VTK local node i = canonical local node perm[i].
const std::vector<int>& permutation_for(int type, CellShape shape) {
  static std::mutex mutex;
  static std::map<std::pair<int, int>, std::vector<int>> cache;
  const int n = num_lagrange_nodes(shape.kind, shape.order);
  std::lock_guard lock(mutex);
  auto [it, inserted] = cache.try_emplace({type, n});
  if (inserted) {
    try {
      it->second =
          detail::match_reference_nodes(vtk_reference_coordinates(type, n), shape.kind, shape.order,
                                        k_match_tolerance, "VTK cell type " + std::to_string(type));
    } catch (...) {
      cache.erase(it);
      throw;
    }
  }
  return it->second;
}

/// Collects VTK error and warning events so that they neither reach stderr nor go unnoticed.
class MessageCapture : public vtkCommand {
 public:
  static MessageCapture* New() { return new MessageCapture; }
  void Execute(vtkObject*, unsigned long event, void* data) override {
    const std::string text = data ? static_cast<const char*>(data) : "(no message)";
    if (event == vtkCommand::ErrorEvent) {
      if (!errors.empty()) errors += "; ";
      errors += trim(text);
    } else {
      log::debug("VTK warning: ", trim(text));
    }
  }
  std::string errors;

 private:
  static std::string trim(std::string s) {
    while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
    // VTK prefixes "ERROR: In <source file>, line N\n<class> (<address>): "; keep the message.
    const auto newline = s.find('\n');
    const auto colon = s.find("): ", newline == std::string::npos ? 0 : newline);
    if (newline != std::string::npos && colon != std::string::npos) s = s.substr(colon + 3);
    return s;
  }
};

/// While any instance is alive, VTK's logger writes nothing to stderr: VTK objects we cannot
/// observe (the pipeline executive, the zlib decompressor) would otherwise print errors for every
/// bad file. The errors that matter reach MessageCapture through the reader's and writer's
/// observers. Reference-counted, so concurrent readers restore the previous level only once.
class QuietVtkLogger {
 public:
  QuietVtkLogger() {
    std::lock_guard lock(mutex());
    if (depth()++ == 0) {
      saved() = vtkLogger::GetCurrentVerbosityCutoff();
      vtkLogger::SetStderrVerbosity(vtkLogger::VERBOSITY_OFF);
    }
  }
  ~QuietVtkLogger() {
    std::lock_guard lock(mutex());
    if (--depth() == 0) vtkLogger::SetStderrVerbosity(saved());
  }
  QuietVtkLogger(const QuietVtkLogger&) = delete;
  QuietVtkLogger& operator=(const QuietVtkLogger&) = delete;

 private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  static int& depth() {
    static int d = 0;
    return d;
  }
  static vtkLogger::Verbosity& saved() {
    static vtkLogger::Verbosity v = vtkLogger::VERBOSITY_WARNING;
    return v;
  }
};

void check_fields(const std::vector<Field>& fields, long long count, const char* where,
                  const std::filesystem::path& path) {
  std::set<std::string> names;
  for (const Field& f : fields) {
    const std::string label = std::string(where) + " field '" + f.name + "'";
    if (f.name.empty())
      throw InputError(std::string(where) + " field without a name", {.file = path.string()});
    if (!names.insert(f.name).second)
      throw InputError(label + " appears twice", {.file = path.string()});
    if (f.components < 1)
      throw InputError(label + " has " + std::to_string(f.components) + " components",
                       {.file = path.string()});
    if (static_cast<long long>(f.values.size()) != count * f.components)
      throw InputError(label + " has " + std::to_string(f.values.size()) + " values, expected " +
                           std::to_string(count) + " × " + std::to_string(f.components),
                       {.file = path.string()});
  }
}

vtkSmartPointer<vtkDoubleArray> to_vtk_array(const Field& f, vtkIdType tuples) {
  auto array = vtkSmartPointer<vtkDoubleArray>::New();
  array->SetName(f.name.c_str());
  array->SetNumberOfComponents(f.components);
  array->SetNumberOfTuples(tuples);
  std::copy(f.values.begin(), f.values.end(), array->GetPointer(0));
  return array;
}

/// All numeric arrays of `data` as fields; the 1-component integer-valued `tag_name` array (if
/// any, and if `tag_name` is non-null) goes to `tags` instead.
std::vector<Field> from_vtk_arrays(vtkFieldData* data, vtkIdType tuples, const char* tag_name,
                                   Eigen::VectorXi* tags) {
  std::vector<Field> fields;
  for (int a = 0; a < data->GetNumberOfArrays(); ++a) {
    vtkDataArray* array = data->GetArray(a);
    if (array == nullptr) continue;  // string or other non-numeric array
    if (array->GetNumberOfTuples() != tuples) continue;
    const char* raw_name = array->GetName();
    const std::string name = raw_name ? raw_name : "array_" + std::to_string(a);
    const int components = array->GetNumberOfComponents();
    if (tag_name != nullptr && name == tag_name && components == 1 &&
        array->GetDataType() != VTK_FLOAT && array->GetDataType() != VTK_DOUBLE) {
      tags->resize(tuples);
      for (vtkIdType i = 0; i < tuples; ++i)
        (*tags)[i] = static_cast<int>(array->GetComponent(i, 0));
      continue;
    }
    Field f{.name = name, .components = components, .values = {}};
    f.values.resize(static_cast<std::size_t>(tuples) * components);
    for (vtkIdType i = 0; i < tuples; ++i)
      for (int c = 0; c < components; ++c) f.values[i * components + c] = array->GetComponent(i, c);
    fields.push_back(std::move(f));
  }
  return fields;
}

}  // namespace

std::vector<int> vtk_node_permutation(CellKind kind, int order) {
  if (order < 1 || order > k_max_order)
    throw InputError("VTK node permutation: order " + std::to_string(order) + " is not in 1.." +
                     std::to_string(k_max_order));
  return permutation_for(vtk_cell_type(kind, order), CellShape{kind, order});
}

void write_vtu(const std::filesystem::path& path, const LagrangeMesh& mesh,
               const MeshFields& fields) {
  validate_structure(mesh, "write_vtu " + path.string());
  check_fields(fields.point_data, mesh.num_nodes(), "point", path);
  check_fields(fields.cell_data, mesh.num_cells(), "cell", path);
  for (const Field& f : fields.cell_data)
    if (f.name == k_tag_array)
      throw InputError("cell field name 'tag' is reserved for the mesh's cell tags",
                       {.file = path.string()});

  const int n = mesh.nodes_per_cell();
  const int type = vtk_cell_type(mesh.kind, mesh.order);
  const std::vector<int>& perm = vtk_node_permutation(mesh.kind, mesh.order);

  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(mesh.num_nodes());
  for (int i = 0; i < mesh.num_nodes(); ++i)
    points->SetPoint(i, mesh.nodes(i, 0), mesh.nodes(i, 1), mesh.nodes(i, 2));

  auto offsets = vtkSmartPointer<vtkIdTypeArray>::New();
  auto connectivity = vtkSmartPointer<vtkIdTypeArray>::New();
  offsets->SetNumberOfValues(mesh.num_cells() + 1);
  connectivity->SetNumberOfValues(static_cast<vtkIdType>(mesh.num_cells()) * n);
  for (int c = 0; c <= mesh.num_cells(); ++c) offsets->SetValue(c, static_cast<vtkIdType>(c) * n);
  for (int c = 0; c < mesh.num_cells(); ++c)
    for (int i = 0; i < n; ++i)
      connectivity->SetValue(static_cast<vtkIdType>(c) * n + i, mesh.cells(c, perm[i]));
  auto cells = vtkSmartPointer<vtkCellArray>::New();
  cells->SetData(offsets, connectivity);
  auto types = vtkSmartPointer<vtkUnsignedCharArray>::New();
  types->SetNumberOfValues(mesh.num_cells());
  for (int c = 0; c < mesh.num_cells(); ++c) types->SetValue(c, static_cast<unsigned char>(type));

  auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
  grid->SetPoints(points);
  grid->SetCells(types, cells);
  for (const Field& f : fields.point_data)
    grid->GetPointData()->AddArray(to_vtk_array(f, mesh.num_nodes()));
  for (const Field& f : fields.cell_data)
    grid->GetCellData()->AddArray(to_vtk_array(f, mesh.num_cells()));
  if (mesh.cell_tags.size() > 0) {
    auto tags = vtkSmartPointer<vtkIntArray>::New();
    tags->SetName(k_tag_array);
    tags->SetNumberOfValues(mesh.num_cells());
    for (int c = 0; c < mesh.num_cells(); ++c) tags->SetValue(c, mesh.cell_tags[c]);
    grid->GetCellData()->AddArray(tags);
  }

  AtomicFile file(path);
  const QuietVtkLogger quiet;
  auto capture = vtkSmartPointer<MessageCapture>::New();
  auto writer = vtkSmartPointer<vtkXMLUnstructuredGridWriter>::New();
  writer->AddObserver(vtkCommand::ErrorEvent, capture);
  writer->AddObserver(vtkCommand::WarningEvent, capture);
  writer->SetInputData(grid);
  writer->SetFileName(file.temp_path().c_str());
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();  // raw binary, not base64
  writer->SetCompressorTypeToZLib();
  writer->SetHeaderTypeToUInt64();
  writer->SetIdTypeToInt64();
  if (writer->Write() == 0 || !capture->errors.empty())
    throw IoError("VTK XML writer failed: " +
                      (capture->errors.empty() ? std::string("no message") : capture->errors),
                  {.file = path.string()});
  file.commit();
  log::debug("wrote ", path.string(), ": ", mesh.num_cells(), " ", kind_name(mesh.kind),
             "s of order ", mesh.order, ", ", mesh.num_nodes(), " nodes");
}

VtuContent read_vtu(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))  // as every reader: cannot open = I/O failure
    throw IoError(std::filesystem::exists(path, ec) ? "not a regular file" : "file not found",
                  {.file = file});

  const QuietVtkLogger quiet;
  auto capture = vtkSmartPointer<MessageCapture>::New();
  auto reader = vtkSmartPointer<vtkXMLUnstructuredGridReader>::New();
  reader->AddObserver(vtkCommand::ErrorEvent, capture);
  reader->AddObserver(vtkCommand::WarningEvent, capture);
  reader->SetReaderErrorObserver(capture);
  reader->SetParserErrorObserver(capture);
  if (reader->CanReadFile(file.c_str()) == 0)
    throw InputError("not a VTK XML UnstructuredGrid file (.vtu)" +
                         (capture->errors.empty() ? std::string() : ": " + capture->errors),
                     {.file = file});
  {
    // VTK trusts sizes in the file; corrupted ones crash it (see vtu_binary_check.hpp).
    std::ifstream in(path, std::ios::binary);
    const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    if (!in && !in.eof()) throw IoError("cannot read file", {.file = file});
    detail::check_vtu_before_vtk(bytes, file);
  }
  reader->SetFileName(file.c_str());
  try {
    reader->Update();
  } catch (const std::exception& e) {
    // A corrupted compression header can make VTK attempt a huge allocation (std::bad_alloc).
    throw InputError(std::string("unreadable VTU file: ") + e.what(), {.file = file});
  }
  vtkUnstructuredGrid* grid = reader->GetOutput();
  if (!capture->errors.empty() || reader->GetErrorCode() != 0 || grid == nullptr)
    throw InputError(
        "unreadable VTU file" + (capture->errors.empty() ? std::string() : ": " + capture->errors),
        {.file = file});
  const vtkIdType num_points = grid->GetNumberOfPoints();
  const vtkIdType num_cells = grid->GetNumberOfCells();
  if (num_points == 0 || num_cells == 0 || grid->GetPoints() == nullptr)
    throw InputError("VTU file has " + std::to_string(num_points) + " points and " +
                         std::to_string(num_cells) + " cells (empty or truncated?)",
                     {.file = file});

  VtuContent content;
  LagrangeMesh& mesh = content.mesh;
  mesh.nodes.resize(num_points, 3);
  for (vtkIdType i = 0; i < num_points; ++i) {
    double x[3];
    grid->GetPoints()->GetPoint(i, x);
    for (int d = 0; d < 3; ++d) {
      if (!std::isfinite(x[d]))
        throw InputError("non-finite point coordinate", {.file = file, .vertex = i});
      mesh.nodes(i, d) = x[d];
    }
  }

  std::optional<CellShape> first;
  for (vtkIdType c = 0; c < num_cells; ++c) {
    const int type = grid->GetCellType(c);
    vtkIdType npts = 0;
    const vtkIdType* ids = nullptr;
    grid->GetCellPoints(c, npts, ids);
    const std::optional<CellShape> shape = classify(type, npts);
    if (!shape)
      throw InputError("unsupported cell: VTK type " + std::to_string(type) + " with " +
                           std::to_string(npts) +
                           " points (accepted: complete Lagrange triangles/tetrahedra of order "
                           "1.." +
                           std::to_string(k_max_order) + ", types 5/10/22/24/69/71)",
                       {.file = file, .element = c});
    if (!first) {
      first = shape;
      mesh.kind = shape->kind;
      mesh.order = shape->order;
      mesh.cells.resize(num_cells, npts);
    } else if (shape->kind != first->kind || shape->order != first->order) {
      throw InputError(std::string("mixed cells: a ") + kind_name(shape->kind) + " of order " +
                           std::to_string(shape->order) + " after " + kind_name(first->kind) +
                           "s of order " + std::to_string(first->order) +
                           " (one kind and order per file)",
                       {.file = file, .element = c});
    }
    const std::vector<int>& perm = permutation_for(type, *shape);
    for (vtkIdType i = 0; i < npts; ++i) {
      if (ids[i] < 0 || ids[i] >= num_points)
        throw InputError("point id " + std::to_string(ids[i]) + " out of range [0, " +
                             std::to_string(num_points) + ")",
                         {.file = file, .element = c});
      mesh.cells(c, perm[i]) = static_cast<int>(ids[i]);
    }
  }

  content.fields.point_data = from_vtk_arrays(grid->GetPointData(), num_points, nullptr, nullptr);
  content.fields.cell_data =
      from_vtk_arrays(grid->GetCellData(), num_cells, k_tag_array, &mesh.cell_tags);
  log::debug("read ", file, ": ", num_cells, " ", kind_name(mesh.kind), "s of order ", mesh.order,
             ", ", num_points, " nodes");
  return content;
}

}  // namespace curvefem::io
