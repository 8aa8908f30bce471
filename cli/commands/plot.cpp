#include "commands/plot.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>

#include "commands/command.hpp"
#include "commands/output_file.hpp"
#include "commands/record.hpp"
#include "commands/xml.hpp"

namespace arbiter::cli {

namespace {

using Json = nlohmann::ordered_json;

constexpr double kLeft = 200;  // room for the row labels
constexpr double kWidth = 900;
constexpr double kRight = 20;
constexpr double kTop = 58;  // title, legend and step axis
constexpr double kRow = 30;
constexpr double kPad = 4;  // between rows
constexpr double kSection = 22;
constexpr const char* kComponentColours[] = {"#d62728", "#2ca02c", "#1f77b4", "#9467bd"};
constexpr const char* kStateColours[] = {"#c6dbef", "#fdd0a2", "#c7e9c0", "#dadaeb", "#fcbba1"};

const Json& member(const Json& object, const std::string& key) {
  static const Json kNull;
  if (!object.is_object()) return kNull;
  const auto found = object.find(key);
  return found == object.end() ? kNull : *found;
}

double number_or(const Json& value, double fallback) {
  return value.is_number() ? value.get<double>() : fallback;
}

/// Tick spacing for the step axis: 1, 2, 5, 10, 20, 50... with at most about 12 ticks.
std::uint64_t tick_spacing(std::size_t steps) {
  std::uint64_t spacing = 1;
  for (int i = 0; steps / spacing > 12; ++i) spacing *= (i % 3 == 1) ? 5 : 2;
  return spacing;
}

class Plot {
 public:
  Plot(const TraceFile& trace)
      : trace_(&trace), n_(std::max<std::size_t>(trace.records.size(), 1)) {}

  /// Draws `other`'s row of each behaviour under this trace's, with the steps where they differ.
  void compare_with(const TraceFile& other) {
    other_ = &other;
    n_ = std::max<double>(n_, static_cast<double>(other.records.size()));
  }

  double x(std::size_t index) const { return kLeft + kWidth * static_cast<double>(index) / n_; }

  /// Starts a row: its `<g>`, background and label; returns the row's top.
  double open_row(const std::string& kind, const std::string& name, const std::string& label) {
    const double top = y_;
    const bool compared = other_ != nullptr && trace_ == other_;
    body_ += fmt::format(R"(<g class="row {}{}" data-name="{}">)", kind,
                         compared ? " compared" : "", xml_escaped(name));
    body_ += fmt::format(R"(<title>{}</title>)", xml_escaped(name));
    body_ += fmt::format(R"(<rect x="{}" y="{}" width="{}" height="{}" fill="#f4f4f4"/>)", kLeft,
                         top, kWidth, kRow);
    body_ += fmt::format(R"(<text x="{}" y="{:.1f}" text-anchor="end">{}</text>)", kLeft - 8,
                         top + kRow / 2 + 4, xml_escaped(label));
    y_ += kRow + kPad;
    return top;
  }
  void close_row() { body_ += "</g>\n"; }

  void section(const std::string& title) {
    y_ += 6;
    body_ += fmt::format(R"(<text x="8" y="{:.1f}" font-weight="bold">{}</text>)", y_ + 10,
                         xml_escaped(title));
    body_ += "\n";
    y_ += kSection - 6;
  }

  /// A step function over the records as a closed area (from the row's bottom) or a line.
  std::string steps_path(const std::vector<double>& values, double top, bool area) const {
    const double bottom = top + kRow;
    const auto y_of = [&](double v) {
      return bottom - std::clamp(std::isfinite(v) ? v : 0.0, 0.0, 1.0) * (kRow - 2);
    };
    std::string d = area ? fmt::format("M{:.1f},{:.1f}", x(0), bottom) : "";
    for (std::size_t i = 0; i < values.size(); ++i) {
      d += fmt::format("{}{:.1f},{:.1f}L{:.1f},{:.1f}", d.empty() ? "M" : "L", x(i),
                       y_of(values[i]), x(i + 1), y_of(values[i]));
    }
    if (area) d += fmt::format("L{:.1f},{:.1f}Z", x(values.size()), bottom);
    return d;
  }

  /// A row drawn by `draw` (given its label, it returns the row's top); comparing, the other
  /// run's under it, with the steps where `differs` (given both runs' records) shaded.
  template <typename Draw, typename Differs>
  void rows(const std::string& label, Draw draw, Differs differs) {
    if (other_ == nullptr) {
      draw(label);
      return;
    }
    const TraceFile* first = trace_;
    draw(label + " (A)");
    trace_ = other_;
    const double top = draw(label + " (B)");
    trace_ = first;
    const std::size_t common = std::min(first->records.size(), other_->records.size());
    for (std::size_t i = 0; i < common; ++i) {
      if (!differs(first->records[i], other_->records[i])) continue;
      body_ += fmt::format(
          R"(<rect class="divergent" x="{:.1f}" y="{:.1f}" width="{:.1f}" height="{}" fill="#ff7f0e" fill-opacity="0.45"><title>step {}: the runs differ</title></rect>)",
          x(i), top, std::max(x(i + 1) - x(i), 1.0), kRow, step_at(i));
    }
  }

  void behaviour(const std::string& layer, const std::string& name) {
    rows(
        name, [&](const std::string& label) { return behaviour_row(layer, name, label); },
        [&](const Json& a_record, const Json& b_record) {
          const Json& a = member(member(member(a_record, "layers"), layer), name);
          const Json& b = member(member(member(b_record, "layers"), layer), name);
          return (member(a, "active") == true) != (member(b, "active") == true) ||
                 std::fabs(number_or(member(a, "activation"), 0.0) -
                           number_or(member(b, "activation"), 0.0)) > 1e-9;
        });
  }

  void controller(const std::string& name) {
    rows(
        name, [&](const std::string& label) { return controller_row(name, label); },
        [&](const Json& a_record, const Json& b_record) {
          const Json& a = member(member(a_record, "controllers"), name);
          const Json& b = member(member(b_record, "controllers"), name);
          return member(a, "state") != member(b, "state") ||
                 member(a, "events") != member(b, "events");
        });
  }

  void actuator(const std::string& name) {
    rows(
        name, [&](const std::string& label) { return actuator_row(name, label); },
        [&](const Json& a_record, const Json& b_record) {
          const Json& a = member(member(a_record, "actuators"), name);
          const Json& b = member(member(b_record, "actuators"), name);
          return member(a, "written") != member(b, "written") ||
                 !close(member(a, "value"), member(b, "value"));
        });
  }

  /// Equal values, numbers within 1e-9 (as `arbiter diff` compares by default).
  static bool close(const Json& a, const Json& b) {
    if (a.is_number() && b.is_number()) return std::fabs(a.get<double>() - b.get<double>()) <= 1e-9;
    if (a.is_array() && b.is_array() && a.size() == b.size()) {
      for (std::size_t i = 0; i < a.size(); ++i) {
        if (!close(a[i], b[i])) return false;
      }
      return true;
    }
    return a == b;
  }

  double behaviour_row(const std::string& layer, const std::string& name,
                       const std::string& label) {
    std::vector<double> activation;
    std::vector<double> requested;
    std::vector<char> active;
    for (const auto& record : trace_->records) {
      const Json& entry = member(member(member(record, "layers"), layer), name);
      activation.push_back(number_or(member(entry, "activation"), 0.0));
      requested.push_back(number_or(member(entry, "requested"), 0.0));
      active.push_back(member(entry, "active") == true ? 1 : 0);
    }
    const double top = open_row("behaviour", layer + "/" + name, label);
    body_ += fmt::format(R"(<path class="activation" d="{}" fill="#4c9be8" fill-opacity="0.55"/>)",
                         steps_path(activation, top, true));
    body_ += fmt::format(
        R"(<path class="requested" d="{}" fill="none" stroke="#1b3a5c" stroke-width="1" stroke-dasharray="3,2"/>)",
        steps_path(requested, top, false));
    for (std::size_t i = 0; i < active.size();) {
      if (active[i] == 0) {
        ++i;
        continue;
      }
      const std::size_t begin = i;
      while (i < active.size() && active[i] != 0) ++i;
      body_ += fmt::format(
          R"(<rect class="active" x="{:.1f}" y="{:.1f}" width="{:.1f}" height="3" fill="#2ca02c"/>)",
          x(begin), top + kRow - 3, x(i) - x(begin));
    }
    // Ticks where the behaviour became active (green) or inactive (red).
    for (std::size_t i = 1; i < active.size(); ++i) {
      if (active[i] == active[i - 1]) continue;
      body_ += fmt::format(
          R"(<line class="event" x1="{:.1f}" y1="{:.1f}" x2="{:.1f}" y2="{:.1f}" stroke="{}" stroke-width="1.5"><title>step {}: {}</title></line>)",
          x(i), top, x(i), top + kRow, active[i] ? "#2ca02c" : "#d62728", step_at(i),
          active[i] ? "activated" : "deactivated");
    }
    close_row();
    return top;
  }

  double controller_row(const std::string& name, const std::string& label) {
    const double top = open_row("controller", "state_machines/" + name, label);
    std::size_t begin = 0;
    std::string state;
    std::size_t colour = 0;
    const auto segment = [&](std::size_t end) {
      if (state.empty() || end <= begin) return;
      body_ += fmt::format(
          R"(<rect x="{:.1f}" y="{}" width="{:.1f}" height="{}" fill="{}"><title>{}</title></rect>)",
          x(begin), top, x(end) - x(begin), kRow, kStateColours[colour % std::size(kStateColours)],
          xml_escaped(state));
      if (x(end) - x(begin) > 7.0 * static_cast<double>(state.size())) {
        body_ += fmt::format(R"(<text x="{:.1f}" y="{:.1f}">{}</text>)", x(begin) + 3,
                             top + kRow / 2 + 4, xml_escaped(state));
      }
      ++colour;
    };
    for (std::size_t i = 0; i < trace_->records.size(); ++i) {
      const Json& entry = member(member(trace_->records[i], "controllers"), name);
      const Json& now = member(entry, "state");
      const std::string current = now.is_string() ? now.get<std::string>() : "";
      if (current != state) {
        segment(i);
        state = current;
        begin = i;
      }
      const Json& events = member(entry, "events");
      if (!events.is_array() || events.empty()) continue;
      std::string text;
      for (const auto& event : events) {
        if (event.is_string()) text += (text.empty() ? "" : ", ") + event.get<std::string>();
      }
      body_ += fmt::format(
          R"(<line class="event" x1="{:.1f}" y1="{}" x2="{:.1f}" y2="{}" stroke="#333" stroke-width="1"><title>step {}: {}</title></line>)",
          x(i), top, x(i), top + 6, step_at(i), xml_escaped(text));
    }
    segment(trace_->records.size());
    close_row();
    return top;
  }

  double actuator_row(const std::string& name, const std::string& label) {
    // One series per component: a number or bool is one, a vector one per element.
    std::vector<std::vector<double>> series;
    bool text_valued = false;
    for (std::size_t i = 0; i < trace_->records.size(); ++i) {
      const Json& value = member(member(member(trace_->records[i], "actuators"), name), "value");
      std::vector<double> components;
      if (value.is_boolean()) {
        components.push_back(value.get<bool>() ? 1.0 : 0.0);
      } else if (value.is_number()) {
        components.push_back(value.get<double>());
      } else if (value.is_array()) {
        for (const auto& item : value) components.push_back(number_or(item, 0.0));
      } else {
        text_valued = true;
      }
      if (series.size() < components.size()) {
        series.resize(components.size(), std::vector<double>(i, 0.0));
      }
      for (std::size_t c = 0; c < series.size(); ++c) {
        series[c].push_back(c < components.size() ? components[c] : 0.0);
      }
    }
    double low = std::numeric_limits<double>::infinity();
    double high = -low;
    for (const auto& values : series) {
      for (const double v : values) {
        if (!std::isfinite(v)) continue;
        low = std::min(low, v);
        high = std::max(high, v);
      }
    }
    if (!(low <= high)) low = high = 0.0;
    if (high - low < 1e-12) {
      low -= 0.5;
      high += 0.5;
    }
    const double top = open_row("actuator", name, label);
    for (std::size_t c = 0; c < series.size(); ++c) {
      std::vector<double> scaled;
      for (const double v : series[c]) scaled.push_back((v - low) / (high - low));
      body_ += fmt::format(R"(<path d="{}" fill="none" stroke="{}" stroke-width="1.2"/>)",
                           steps_path(scaled, top, false),
                           kComponentColours[c % std::size(kComponentColours)]);
    }
    if (!series.empty()) {
      body_ += fmt::format(R"(<text x="{}" y="{}" font-size="9" fill="#666">{:.3g}</text>)",
                           kLeft + kWidth + 2, top + 8, high);
      body_ += fmt::format(R"(<text x="{}" y="{}" font-size="9" fill="#666">{:.3g}</text>)",
                           kLeft + kWidth + 2, top + kRow, low);
    } else if (text_valued) {
      body_ += fmt::format(R"(<text x="{}" y="{}" fill="#666">(not a number)</text>)", kLeft + 4,
                           top + kRow / 2 + 4);
    }
    close_row();
    return top;
  }

  std::string finish(const std::string& title, const std::string& subtitle) {
    const double height = y_ + 30;
    const double width = kLeft + kWidth + kRight + 24;
    std::string out = fmt::format(
        R"(<?xml version="1.0" encoding="UTF-8"?>)"
        "\n"
        R"(<svg xmlns="http://www.w3.org/2000/svg" width="{0}" height="{1}" viewBox="0 0 {0} {1}" font-family="DejaVu Sans, sans-serif" font-size="11">)"
        "\n"
        R"(<rect width="100%" height="100%" fill="white"/>)"
        "\n"
        R"(<text x="8" y="18" font-size="14" font-weight="bold">{2}</text>)"
        R"(<text x="8" y="34" fill="#444">{3}</text>)"
        "\n",
        width, height, xml_escaped(title), xml_escaped(subtitle));
    // Step axis, with grid lines through every row.
    const auto spacing = tick_spacing(trace_->records.size());
    out += R"(<g class="axis">)";
    for (std::size_t i = 0; i < trace_->records.size(); ++i) {
      const auto step = step_at(i);
      if (step % spacing != 0) continue;
      const double at = (x(i) + x(i + 1)) / 2;
      out += fmt::format(
          R"(<line x1="{0:.1f}" y1="{1}" x2="{0:.1f}" y2="{2}" stroke="#ddd"/><text x="{0:.1f}" y="{3}" text-anchor="middle" fill="#444">{4}</text>)",
          at, kTop - 6, y_, kTop - 10, step);
    }
    out += fmt::format(R"(<text x="{}" y="{}" text-anchor="end" fill="#444">step</text>)",
                       kLeft - 8, kTop - 10);
    out += "</g>\n";
    out += body_;
    out += fmt::format(
        R"svg(<g class="legend" transform="translate({},{})">)svg"
        R"(<rect width="14" height="10" fill="#4c9be8" fill-opacity="0.55"/><text x="18" y="9">activation</text>)"
        R"(<line x1="90" y1="5" x2="104" y2="5" stroke="#1b3a5c" stroke-dasharray="3,2"/><text x="108" y="9">requested</text>)"
        R"(<rect x="180" y="7" width="14" height="3" fill="#2ca02c"/><text x="198" y="9">active</text>)"
        R"(<line x1="250" y1="0" x2="250" y2="10" stroke="#2ca02c" stroke-width="1.5"/><line x1="254" y1="0" x2="254" y2="10" stroke="#d62728" stroke-width="1.5"/><text x="260" y="9">became active / inactive</text>)"
        "</g>\n",
        kLeft, height - 20);
    out += "</svg>\n";
    return out;
  }

  /// True when behaviour or interface code reported something (the records' "reported").
  bool has_reported() const {
    return std::any_of(trace_->records.begin(), trace_->records.end(),
                       [](const Json& record) { return member(record, "reported").is_array(); });
  }

  /// One row with a tick per reported event, labelled where there is room for the text.
  void reported() {
    const double top = open_row("reported", "reported", "reported by code");
    double label_end = 0;  // right edge of the last label drawn
    for (std::size_t i = 0; i < trace_->records.size(); ++i) {
      const Json& reported = member(trace_->records[i], "reported");
      if (!reported.is_array() || reported.empty()) continue;
      std::string text;
      for (const auto& event : reported) {
        const Json& by = member(event, "by");
        const Json& what = member(event, "text");
        if (!what.is_string()) continue;
        if (!text.empty()) text += "; ";
        text += (by.is_string() ? by.get<std::string>() + ": " : "") + what.get<std::string>();
      }
      const double at = x(i) + (x(i + 1) - x(i)) / 2;
      body_ += fmt::format(
          R"(<line class="event" x1="{0:.1f}" y1="{1:.1f}" x2="{0:.1f}" y2="{2:.1f}" stroke="#e6550d" stroke-width="2"><title>step {3}: {4}</title></line>)",
          at, top + 2, top + kRow - 2, step_at(i), xml_escaped(text));
      const Json& first = member(reported.front(), "text");
      const std::string label = first.is_string() ? first.get<std::string>() : "";
      // About 7 px per character at the plot's font size; overlapping labels are left out (the
      // tick's tooltip still has the text).
      if (at + 3 >= label_end && !label.empty()) {
        body_ += fmt::format(
            R"(<text class="reported-label" x="{:.1f}" y="{:.1f}" font-size="11" fill="#a63603">{}</text>)",
            at + 3, top + kRow / 2 + 4, xml_escaped(label));
        label_end = at + 3 + 7.0 * static_cast<double>(label.size());
      }
    }
    close_row();
  }

  /// A dashed line through every row where a reload swapped a new program in.
  void reloads() {
    for (const auto& reload : trace_->reloads) {
      body_ += fmt::format(
          R"(<line class="reload" x1="{0:.1f}" y1="{1}" x2="{0:.1f}" y2="{2}" stroke="#7a5af8" stroke-width="1.5" stroke-dasharray="5,3"><title>config reloaded after step {3}</title></line>)",
          x(reload.before), kTop - 4, y_, member(reload.header, "after_step").dump());
    }
  }

  std::uint64_t step_at(std::size_t index) const {
    return index < trace_->records.size() ? trace_->records[index]["step"].get<std::uint64_t>() : 0;
  }

  double y_ = kTop;

 private:
  const TraceFile* trace_;
  const TraceFile* other_ = nullptr;
  double n_;
  std::string body_;
};

/// The layers and behaviours of every program of the run, each once, in the order they first
/// appear: the first header's, then what reloads added.
std::vector<std::pair<std::string, std::vector<std::string>>> behaviours_of(
    const TraceFile& trace) {
  std::vector<std::pair<std::string, std::vector<std::string>>> layers;
  const auto add = [&](const Json& header) {
    for (const auto& layer : member(header, "layers")) {
      const Json& name = member(layer, "name");
      if (!name.is_string()) continue;
      auto found = std::find_if(layers.begin(), layers.end(),
                                [&](const auto& item) { return item.first == name; });
      if (found == layers.end()) {
        layers.emplace_back(name.get<std::string>(), std::vector<std::string>{});
        found = layers.end() - 1;
      }
      for (const auto& behaviour : member(layer, "order")) {
        if (!behaviour.is_string()) continue;
        auto& names = found->second;
        if (std::find(names.begin(), names.end(), behaviour) == names.end()) {
          names.push_back(behaviour.get<std::string>());
        }
      }
    }
  };
  add(trace.header);
  for (const auto& reload : trace.reloads) add(reload.header);
  return layers;
}

/// The names of the members of `key` ("controllers", "actuators") in the first records of the
/// runs, each once: the first run's, then what only the second has.
std::vector<std::string> names_of(const std::string& key, const TraceFile& trace,
                                  const TraceFile* other) {
  std::vector<std::string> names;
  for (const TraceFile* run : {&trace, other}) {
    if (run == nullptr || run->records.empty()) continue;
    const Json& items = member(run->records.front(), key);
    if (!items.is_object()) continue;
    for (const auto& item : items.items()) {
      if (std::find(names.begin(), names.end(), item.key()) == names.end()) {
        names.push_back(item.key());
      }
    }
  }
  return names;
}

}  // namespace

std::string plot_svg(const TraceFile& trace, const PlotOptions& options) {
  Plot plot(trace);
  if (options.compare != nullptr) plot.compare_with(*options.compare);
  if (plot.has_reported()) {
    plot.section("events");
    plot.reported();
  }
  auto layers = behaviours_of(trace);
  if (options.compare != nullptr) {
    // What only the second run has gets its rows too.
    for (const auto& other : behaviours_of(*options.compare)) {
      auto found = std::find_if(layers.begin(), layers.end(),
                                [&](const auto& item) { return item.first == other.first; });
      if (found == layers.end()) {
        layers.push_back(other);
        continue;
      }
      for (const auto& name : other.second) {
        if (std::find(found->second.begin(), found->second.end(), name) == found->second.end()) {
          found->second.push_back(name);
        }
      }
    }
  }
  for (const auto& [layer, names] : layers) {
    if (names.empty()) continue;
    plot.section("layer " + layer);
    for (const auto& name : names) plot.behaviour(layer, name);
  }
  if (const auto machines = names_of("controllers", trace, options.compare); !machines.empty()) {
    plot.section("state machines");
    for (const auto& machine : machines) plot.controller(machine);
  }
  if (const auto actuators = names_of("actuators", trace, options.compare);
      options.actuators && !actuators.empty()) {
    plot.section("actuators");
    for (const auto& actuator : actuators) plot.actuator(actuator);
  }
  const Json& name = member(trace.header, "name");
  const std::string title = name.is_string() ? name.get<std::string>() : "trace";
  std::string subtitle =
      trace.records.empty()
          ? "no steps"
          : fmt::format("steps {} to {}", trace.records.front()["step"].get<std::uint64_t>(),
                        trace.records.back()["step"].get<std::uint64_t>());
  if (options.compare != nullptr) {
    subtitle = fmt::format(
        "A: {} ({} steps), B: {} ({} steps); under each row of A, B's, the steps where they "
        "differ shaded",
        options.name_a, trace.records.size(), options.name_b, options.compare->records.size());
  }
  plot.reloads();
  return plot.finish(title, subtitle);
}

int plot_command(const Options& options) {
  // Named, not braced into the call: GCC 12 at -O3 warns, falsely, that a braced temporary's
  // string may be destroyed uninitialised.
  const std::vector<CommandOutput> written = {{options.output, "-o"}};
  const std::vector<CommandInput> read = {{options.trace_path, "the trace being plotted"},
                                          {options.compare_path, "the run compared (--compare)"}};
  if (options.output != "-" && !outputs_allowed("plot", written, read, std::cerr)) {
    return kExitUsage;
  }
  std::string error;
  const auto trace = read_trace_file(options.trace_path, error, options.diagnostic_format);
  if (!trace) {
    std::cerr << error << "\n";
    return kExitInvalid;
  }
  note_end(options.trace_path, trace->truncated, trace->damaged, std::cerr);
  PlotOptions plot_options;
  plot_options.actuators = options.actuators;
  std::optional<TraceFile> compare;  // --compare
  if (!options.compare_path.empty()) {
    compare = read_trace_file(options.compare_path, error, options.diagnostic_format);
    if (!compare) {
      std::cerr << error << "\n";
      return kExitInvalid;
    }
    note_end(options.compare_path, compare->truncated, compare->damaged, std::cerr);
    plot_options.compare = &*compare;
    plot_options.name_a = options.trace_path;
    plot_options.name_b = options.compare_path;
  }
  const std::string svg = plot_svg(*trace, plot_options);
  if (options.output.empty() || options.output == "-") {
    std::cout << svg;
    return kExitOk;
  }
  OutputStream out;
  if (!out.open(options.output) || !(out << svg << std::flush)) {
    std::cerr << fmt::format("arbiter plot: cannot write '{}': {}\n", options.output, out.error());
    return kExitUsage;
  }
  return kExitOk;
}

}  // namespace arbiter::cli
