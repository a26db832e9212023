#include "pipeline/paraview_script.hpp"

#include <cstdio>

namespace curvefem::pipeline {

std::string python_string_literal(const std::string& text) {
  std::string out = "'";
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (ch == '\\' || ch == '\'') {
      out += '\\';
      out += ch;
    } else if (c < 0x20 || c == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    } else {
      out += ch;  // printable ASCII or a UTF-8 byte (Python source is UTF-8)
    }
  }
  return out + "'";
}

std::string paraview_state_script(const ParaviewScriptOptions& o) {
  const auto py_bool = [](bool b) { return std::string(b ? "True" : "False"); };
  std::string s;
  s +=
      R"PY(# ParaView state script written by `curvefem run --paraview` (paraview.simple, ParaView >= 5.9).
#   paraview --script=open_in_paraview.py      (GUI)
#   pvpython open_in_paraview.py               (batch)
# Left view: volume.vtu, the solution on the curved Lagrange cells. Right view (dense-surface
# methods): surface.vtu, the dense input surface, coloured by the error of the solution there when
# an exact solution is known, else by the solution. The cameras are linked. result.pvd opens both
# parts as one dataset instead.
import os

from paraview.simple import *  # noqa: F401,F403

try:
    HERE = os.path.dirname(os.path.abspath(__file__))
except NameError:  # run without __file__ (e.g. pasted into the Python shell)
    HERE = )PY";
  s += python_string_literal(o.dir.string()) + "\n";
  s += "FIELD = " + python_string_literal(o.field) + "\n";
  s += "VECTOR = " + py_bool(o.components > 1) + "\n";
  s += "HAS_SURFACE = " + py_bool(o.surface) + "\n";
  s += "HAS_ERROR = " + py_bool(o.exact) + "\n";
  s += R"PY(

def show_colored(source, view, array):
    """Shows `source` in `view` coloured by the point array (its magnitude if a vector)."""
    display = Show(source, view)
    if VECTOR:
        ColorBy(display, ('POINTS', array, 'Magnitude'))
    else:
        ColorBy(display, ('POINTS', array))
    display.RescaleTransferFunctionToDataRange(True, False)
    display.SetScalarBarVisibility(view, True)
    return display


layout = CreateLayout(name='curvefem')
volume_view = CreateView('RenderView')
volume = XMLUnstructuredGridReader(registrationName='volume.vtu',
                                   FileName=[os.path.join(HERE, 'volume.vtu')])
volume_display = show_colored(volume, volume_view, FIELD)
volume_display.NonlinearSubdivisionLevel = 2  # draw curved (higher-order) cells curved

if HAS_SURFACE:
    layout.SplitHorizontal(0, 0.5)
    layout.AssignView(1, volume_view)
    surface_view = CreateView('RenderView')
    layout.AssignView(2, surface_view)
    surface = XMLUnstructuredGridReader(registrationName='surface.vtu',
                                        FileName=[os.path.join(HERE, 'surface.vtu')])
    show_colored(surface, surface_view, 'error' if HAS_ERROR else FIELD)
    AddCameraLink(volume_view, surface_view, 'curvefem_camera')
    surface_view.ResetCamera()
else:
    layout.AssignView(0, volume_view)

SetActiveView(volume_view)
volume_view.ResetCamera()
Render(volume_view)
)PY";
  return s;
}

}  // namespace curvefem::pipeline
