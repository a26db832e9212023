#include "meshing/core/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdlib>

namespace curvefem {

ProgressTicker::ProgressTicker(const ProgressFn& fn, std::string stage, std::size_t total)
    : m_fn(fn), m_stage(std::move(stage)), m_total(std::max<std::size_t>(total, 1)), m_next(0) {
  if (m_fn) m_fn(m_stage, 0.0);
}

void ProgressTicker::tick(std::size_t done) {
  if (!m_fn || done < m_next) return;
  m_next = done + std::max<std::size_t>(m_total / 100, 1);
  m_fn(m_stage, std::min(1.0, static_cast<double>(done) / static_cast<double>(m_total)));
}

void ProgressTicker::finish() {
  if (m_fn) m_fn(m_stage, 1.0);
}

ProgressMode TerminalProgress::automatic_mode(bool quiet) {
  if (quiet) return ProgressMode::quiet;
  if (std::getenv("CI") != nullptr) return ProgressMode::quiet;
  return isatty(fileno(stderr)) ? ProgressMode::bar : ProgressMode::lines;
}

TerminalProgress::TerminalProgress(ProgressMode mode, std::FILE* out) : m_mode(mode), m_out(out) {}

TerminalProgress::~TerminalProgress() { end_stage(); }

void TerminalProgress::update(std::string_view stage, double fraction) {
  if (m_mode == ProgressMode::quiet) return;
  if (stage != m_stage) {
    end_stage();
    m_stage = std::string(stage);
    m_stage_watch.reset();
    m_last_draw = -1.0;
  }
  m_fraction = std::clamp(fraction, 0.0, 1.0);
  if (m_mode != ProgressMode::bar) return;
  const double now = m_stage_watch.seconds();
  if (m_last_draw >= 0.0 && now - m_last_draw < 0.1 && m_fraction < 1.0) return;
  m_last_draw = now;
  constexpr int k_width = 30;
  const int filled = static_cast<int>(m_fraction * k_width);
  std::string bar(k_width, ' ');
  std::fill(bar.begin(), bar.begin() + filled, '=');
  if (filled < k_width) bar[filled] = '>';
  std::string eta = "";
  if (m_fraction > 0.02 && m_fraction < 1.0) {
    const double remaining = now * (1.0 - m_fraction) / m_fraction;
    char buf[32];
    std::snprintf(buf, sizeof buf, "  ETA %.0f s", remaining);
    eta = buf;
  }
  std::fprintf(m_out, "\r\033[K%s%-24s [%s] %3d%%%s", m_prefix.c_str(), m_stage.c_str(),
               bar.c_str(), static_cast<int>(m_fraction * 100.0 + 0.5), eta.c_str());
  std::fflush(m_out);
}

void TerminalProgress::end_stage() {
  if (m_stage.empty() || m_mode == ProgressMode::quiet) {
    m_stage.clear();
    return;
  }
  const double t = m_stage_watch.seconds();
  if (m_mode == ProgressMode::bar) std::fprintf(m_out, "\r\033[K");
  if (m_mode != ProgressMode::bar || !m_transient)
    std::fprintf(m_out, "%s%-24s done in %.2f s\n", m_prefix.c_str(), m_stage.c_str(), t);
  std::fflush(m_out);
  m_stage.clear();
}

ProgressFn TerminalProgress::callback() {
  return [this](std::string_view stage, double fraction) { update(stage, fraction); };
}

}  // namespace curvefem
