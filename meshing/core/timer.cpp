#include "meshing/core/timer.hpp"

#include <fstream>
#include <string>

namespace curvefem {

void Timings::add(const std::string& stage, double seconds) {
  for (auto& [name, t] : m_stages) {
    if (name == stage) {
      t += seconds;
      return;
    }
  }
  m_stages.emplace_back(stage, seconds);
}

double Timings::get(const std::string& stage) const {
  for (const auto& [name, t] : m_stages)
    if (name == stage) return t;
  return 0.0;
}

double Timings::total() const {
  double sum = 0.0;
  for (const auto& [name, t] : m_stages) sum += t;
  return sum;
}

double peak_rss_mb() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;  // kB
  }
  return 0.0;
}

}  // namespace curvefem
