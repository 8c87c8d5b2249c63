#include "ui/gui/plot_widget.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "jobs/report/plot_axes.hpp"
#include "ui/gui/palette.hpp"

namespace piezo::gui {

namespace {
double fwd(double v, bool log) { return log ? std::log10(std::max(v, 1e-300)) : v; }
double inv(double v, bool log) { return log ? std::pow(10.0, v) : v; }

// A read-out value (ticks are labelled by plot_axes' tick_label).
std::string fmt(double v) {
  char buf[32];
  double a = std::fabs(v);
  if (a != 0 && (a >= 1e5 || a < 1e-2))
    std::snprintf(buf, sizeof buf, "%.3g", v);
  else
    std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}
}  // namespace

namespace {
std::string ohms(double v) {
  char b[32];
  const double a = std::fabs(v);
  if (a >= 1e6)
    std::snprintf(b, sizeof b, "%.4g Mohm", v / 1e6);
  else if (a >= 1e3)
    std::snprintf(b, sizeof b, "%.4g kohm", v / 1e3);
  else
    std::snprintf(b, sizeof b, "%.4g ohm", v);
  return b;
}
}  // namespace

std::string impedance_readout(std::complex<double> z) {
  char ph[32];
  std::snprintf(ph, sizeof ph, "%.1f deg", std::arg(z) * 180.0 / M_PI);
  return "|Z| " + ohms(std::abs(z)) + "  phase " + ph + "  R " + ohms(z.real()) + "  X " + ohms(z.imag());
}

const Marker* snap_marker(const std::vector<Marker>& markers, float mouse_px,
                          const std::function<float(double)>& to_px, float radius_px) {
  const Marker* best = nullptr;
  float best_d = radius_px;
  for (const auto& m : markers) {
    if (!m.snap) continue;
    const float d = std::fabs(to_px(m.x) - mouse_px);
    if (d <= best_d) {
      best_d = d;
      best = &m;
    }
  }
  return best;
}

std::vector<std::pair<ImU32, std::string>> readout_at(const PlotSpec& spec, double x, const Marker* snapped) {
  std::vector<std::pair<ImU32, std::string>> lines;
  if (snapped && !snapped->label.empty()) lines.emplace_back(IM_COL32(255, 255, 255, 255), snapped->label);
  for (const auto& s : spec.series) {
    // The nearest sample in x, and only inside the series' own x range (a
    // curve that ends at 120 kHz has no value to read at 200 kHz).
    if (!s.listed || s.x.empty() || s.y.size() < s.x.size() || x < s.x.front() || x > s.x.back() ||
        !std::is_sorted(s.x.begin(), s.x.end()))
      continue;
    auto it = std::lower_bound(s.x.begin(), s.x.end(), x);
    std::size_t i = std::min<std::size_t>(static_cast<std::size_t>(it - s.x.begin()), s.x.size() - 1);
    if (i > 0 && x - s.x[i - 1] < s.x[i] - x) --i;
    lines.emplace_back(im_colour(s.colour), s.label + ": " + (s.readout ? s.readout(i) : fmt(s.y[i])));
  }
  for (const auto& band : spec.bands)
    if (!band.detail.empty() && x >= std::min(band.x0, band.x1) && x <= std::max(band.x0, band.x1))
      lines.emplace_back(IM_COL32(255, 255, 255, 255), band.detail);
  return lines;
}

void fit_view(const PlotSpec& spec, PlotView& view, bool all) {
  const auto r = jobs::report::fit_range(spec, all);
  view.x0 = r.x0;
  view.x1 = r.x1;
  view.y0 = r.y0;
  view.y1 = r.y1;
  view.fitted = true;
}

bool plot(const char* id, const PlotSpec& spec, PlotView& view, ImVec2 size) {
  if (!view.fitted) fit_view(spec, view);
  ImGui::PushID(id);
  ImGui::BeginChild("plot", size, true,
                    ImGuiWindowFlags_NoScrollbar | ImGuiWindowFlags_NoScrollWithMouse);
  ImDrawList* dl = ImGui::GetWindowDrawList();
  const ImVec2 p0 = ImGui::GetCursorScreenPos();
  const ImVec2 avail = ImGui::GetContentRegionAvail();
  const float left = 64, bottom = 36, top = 22, right = 10;
  const ImVec2 a(p0.x + left, p0.y + top), b(p0.x + avail.x - right, p0.y + avail.y - bottom);
  view.frame = ImVec4(a.x, a.y, b.x, b.y);
  ImGui::InvisibleButton("canvas", avail);
  const bool hovered = ImGui::IsItemHovered();
  const ImGuiIO& io = ImGui::GetIO();
  const bool log_x = spec.x_scale == Scale::Log, log_y = spec.y_scale == Scale::Log;

  double X0 = fwd(view.x0, log_x), X1 = fwd(view.x1, log_x);
  double Y0 = fwd(view.y0, log_y), Y1 = fwd(view.y1, log_y);
  auto sx = [&](double x) {
    return a.x + static_cast<float>((fwd(x, log_x) - X0) / (X1 - X0)) * (b.x - a.x);
  };
  auto sy = [&](double y) {
    return b.y - static_cast<float>((fwd(y, log_y) - Y0) / (Y1 - Y0)) * (b.y - a.y);
  };

  // Interaction: wheel zooms about the cursor, drag pans, double-click fits.
  if (hovered && io.MouseWheel != 0) {
    double f = std::pow(0.85, io.MouseWheel);
    double cx = X0 + (io.MousePos.x - a.x) / (b.x - a.x) * (X1 - X0);
    double cy = Y0 + (b.y - io.MousePos.y) / (b.y - a.y) * (Y1 - Y0);
    bool only_x = io.KeyShift, only_y = io.KeyCtrl;
    if (!only_y) {
      X0 = cx + (X0 - cx) * f;
      X1 = cx + (X1 - cx) * f;
    }
    if (!only_x) {
      Y0 = cy + (Y0 - cy) * f;
      Y1 = cy + (Y1 - cy) * f;
    }
  }
  if (ImGui::IsItemActive() && ImGui::IsMouseDragging(ImGuiMouseButton_Left)) {
    double dx = -io.MouseDelta.x / (b.x - a.x) * (X1 - X0);
    double dy = io.MouseDelta.y / (b.y - a.y) * (Y1 - Y0);
    X0 += dx;
    X1 += dx;
    Y0 += dy;
    Y1 += dy;
  }
  if (hovered && ImGui::IsMouseDoubleClicked(ImGuiMouseButton_Left)) {
    fit_view(spec, view, /*all=*/true);  // every sample ("Fit views" returns to the spec's frame)
    X0 = fwd(view.x0, log_x);
    X1 = fwd(view.x1, log_x);
    Y0 = fwd(view.y0, log_y);
    Y1 = fwd(view.y1, log_y);
  }
  view.x0 = inv(X0, log_x);
  view.x1 = inv(X1, log_x);
  view.y0 = inv(Y0, log_y);
  view.y1 = inv(Y1, log_y);

  // Frame, grid, ticks.
  dl->AddRectFilled(a, b, kColPlotBg);
  const ImU32 grid = IM_COL32(70, 75, 90, 255), text = IM_COL32(200, 200, 210, 255);
  // Ticks as many as their labels leave room for (jobs/report/plot_axes).
  using jobs::report::axis_ticks;
  using jobs::report::tick_label;
  const float x_label_w = ImGui::CalcTextSize(tick_label(view.x1, spec.x_scale, spec.x_unit).c_str()).x + 6;
  const auto xt = axis_ticks(view.x0, view.x1, spec.x_scale, b.x - a.x, x_label_w);
  const auto yt = axis_ticks(view.y0, view.y1, spec.y_scale, b.y - a.y, ImGui::GetTextLineHeight() + 4);
  const ImU32 minor = (grid & ~IM_COL32_A_MASK) | IM_COL32(0, 0, 0, 110);
  for (double t : xt.minor) dl->AddLine(ImVec2(sx(t), a.y), ImVec2(sx(t), b.y), minor);
  for (double t : yt.minor) dl->AddLine(ImVec2(a.x, sy(t)), ImVec2(b.x, sy(t)), minor);
  for (double t : xt.major) {
    const float x = sx(t);
    dl->AddLine(ImVec2(x, a.y), ImVec2(x, b.y), grid);
    const std::string label = tick_label(t, spec.x_scale, spec.x_unit);
    const float w = ImGui::CalcTextSize(label.c_str()).x;
    dl->AddText(ImVec2(x - 0.5f * w, b.y + 4), text, label.c_str());
  }
  for (double t : yt.major) {
    const float y = sy(t);
    dl->AddLine(ImVec2(a.x, y), ImVec2(b.x, y), grid);
    dl->AddText(ImVec2(p0.x + 2, y - 7), text, tick_label(t, spec.y_scale, spec.y_unit).c_str());
  }
  // Title centred over the frame, the y label at the top left (they overlap
  // when both sit at the left edge and the y label is long).
  const float title_w = ImGui::CalcTextSize(spec.title.c_str()).x;
  dl->AddText(ImVec2(0.5f * (a.x + b.x - title_w), p0.y + 2), text, spec.title.c_str());
  dl->AddText(ImVec2(b.x - ImGui::CalcTextSize(spec.x_label.c_str()).x, b.y + 18), text,
              spec.x_label.c_str());
  dl->AddText(ImVec2(p0.x + 2, p0.y + 2), text, spec.y_label.c_str());

  dl->PushClipRect(a, b, true);
  for (const auto& band : spec.bands) {
    float xa = sx(band.x0), xb = sx(band.x1);
    dl->AddRectFilled(ImVec2(xa, a.y), ImVec2(xb, b.y), im_colour(band.colour));
    if (!band.label.empty() && ImGui::CalcTextSize(band.label.c_str()).x + 4 < xb - xa)
      dl->AddText(ImVec2(xa + 2, b.y - 16), text, band.label.c_str());
  }
  for (const auto& m : spec.markers) {
    float x = sx(m.x);
    dl->AddLine(ImVec2(x, a.y), ImVec2(x, b.y), im_colour(m.colour), 1.0f);
  }
  // Lines keep a vertex only once it is a pixel away from the last one kept:
  // the frequency grids are denser than the screen, and every triangle costs
  // a software rasteriser (llvmpipe under Xvfb) setup time. Points are small
  // squares for the same reason (a filled circle is a dozen triangles).
  std::vector<ImVec2> pts;
  for (const auto& s : spec.series) {
    pts.clear();
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!jobs::report::usable(s.x[i], spec.x_scale) || !jobs::report::usable(s.y[i], spec.y_scale)) continue;
      const ImVec2 p(sx(s.x[i]), sy(s.y[i]));
      const bool last = i + 1 == std::min(s.x.size(), s.y.size());
      if (!s.points && !last && !pts.empty() && std::fabs(p.x - pts.back().x) < 1.0f &&
          std::fabs(p.y - pts.back().y) < 1.0f)
        continue;
      pts.push_back(p);
    }
    if (s.points) {
      for (const auto& p : pts)
        dl->AddRectFilled(ImVec2(p.x - 2, p.y - 2), ImVec2(p.x + 2, p.y + 2), im_colour(s.colour));
    } else if (pts.size() > 1) {
      dl->AddPolyline(pts.data(), static_cast<int>(pts.size()), im_colour(s.colour), 0, static_cast<float>(s.width));
    }
  }
  dl->PopClipRect();

  // Legend, on a translucent backing so that it stays readable over curves.
  float ly = a.y + 4, legend_w = 0;
  int listed = 0;
  for (const auto& s : spec.series)
    if (s.listed) {
      legend_w = std::max(legend_w, ImGui::CalcTextSize(s.label.c_str()).x);
      ++listed;
    }
  if (listed > 0)
    dl->AddRectFilled(ImVec2(b.x - legend_w - 32, ly - 2), ImVec2(b.x - 2, ly + 16.0f * listed + 2),
                      (kColPlotBg & ~IM_COL32_A_MASK) | IM_COL32(0, 0, 0, 200));
  for (const auto& s : spec.series) {
    if (!s.listed) continue;
    float w = ImGui::CalcTextSize(s.label.c_str()).x;
    dl->AddRectFilled(ImVec2(b.x - w - 28, ly + 3), ImVec2(b.x - w - 14, ly + 11), im_colour(s.colour));
    dl->AddText(ImVec2(b.x - w - 8, ly), text, s.label.c_str());
    ly += 16;
  }

  // Hover read-out: cursor position (snapped to a resonance marker within a
  // few pixels) and the nearest point of each series; a right click pins it.
  const std::function<float(double)> to_px = [&](double x) { return sx(x); };
  if (view.pinned) {
    const float px = sx(*view.pinned);
    if (px >= a.x && px <= b.x) {
      dl->AddLine(ImVec2(px, a.y), ImVec2(px, b.y), IM_COL32(255, 220, 0, 160), 1.5f);
      const Marker* m = snap_marker(spec.markers, px, to_px, 0.5f);
      float ty = a.y + 4;
      std::string head = spec.x_label + " = " + fmt(*view.pinned);
      auto lines = readout_at(spec, *view.pinned, m);
      lines.insert(lines.begin(), {IM_COL32(255, 220, 0, 255), head});
      float w = 0;
      for (const auto& l : lines) w = std::max(w, ImGui::CalcTextSize(l.second.c_str()).x);
      dl->AddRectFilled(ImVec2(a.x + 4, ty - 2), ImVec2(a.x + w + 12, ty + 16.0f * lines.size() + 2),
                        IM_COL32(0, 0, 0, 200));
      for (const auto& l : lines) {
        dl->AddText(ImVec2(a.x + 8, ty), l.first, l.second.c_str());
        ty += 16;
      }
    }
  }
  if (hovered && io.MousePos.x >= a.x && io.MousePos.x <= b.x && io.MousePos.y >= a.y &&
      io.MousePos.y <= b.y) {
    const Marker* snapped = snap_marker(spec.markers, io.MousePos.x, to_px);
    double cx = snapped ? snapped->x : inv(X0 + (io.MousePos.x - a.x) / (b.x - a.x) * (X1 - X0), log_x);
    const float line_x = snapped ? sx(snapped->x) : io.MousePos.x;
    dl->AddLine(ImVec2(line_x, a.y), ImVec2(line_x, b.y), IM_COL32(255, 255, 255, snapped ? 140 : 60));
    if (ImGui::IsMouseClicked(ImGuiMouseButton_Right)) {
      if (view.pinned && std::fabs(sx(*view.pinned) - io.MousePos.x) <= kSnapPixels)
        view.pinned.reset();
      else
        view.pinned = cx;
    }
    ImGui::BeginTooltip();
    ImGui::Text("%s = %s", spec.x_label.c_str(), fmt(cx).c_str());
    for (const auto& [col, text] : readout_at(spec, cx, snapped))
      ImGui::TextColored(ImGui::ColorConvertU32ToFloat4(col), "%s", text.c_str());
    ImGui::EndTooltip();
  }
  ImGui::EndChild();
  ImGui::PopID();
  return hovered;
}

}  // namespace piezo::gui
