#include "afford/plots.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace afford {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

struct Box {
  double min = 0, q1 = 0, median = 0, q3 = 0, max = 0;
};

Box box(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  auto q = [&](double p) {
    const double pos = p * (v.size() - 1);
    const std::size_t i = static_cast<std::size_t>(pos);
    return i + 1 < v.size() ? v[i] + (pos - i) * (v[i + 1] - v[i]) : v[i];
  };
  return {v.front(), q(0.25), q(0.5), q(0.75), v.back()};
}

const char* kSystemColour(const std::string& s) {
  return s == "FIX" ? "#e69f00" : s == "IGN" ? "#56b4e9" : "#009e73";
}

// gnuplot colour and point type for an object name like "green circle".
std::string objectStyle(const std::string& name) {
  const std::string colour = name.find("red") != std::string::npos     ? "#d62728"
                             : name.find("green") != std::string::npos ? "#2ca02c"
                                                                       : "#1f77b4";
  const int pt = name.find("square") != std::string::npos ? 5 : name.find("circle") != std::string::npos ? 7 : 3;
  const std::string dash = name.find("green") != std::string::npos ? "2" : name.find("blue") != std::string::npos ? "3" : "1";
  return "lc rgb '" + colour + "' pt " + std::to_string(pt) + " dt " + dash;
}

void runGnuplot(const fs::path& script) {
  const std::string cmd = "gnuplot " + script.string() + " 2>&1";
  if (std::system(cmd.c_str()) != 0) throw std::runtime_error("gnuplot failed on " + script.string());
}

std::string quoted(const std::string& s) { return "'" + s + "'"; }

}  // namespace

std::vector<std::string> plotExperiment(const std::string& dir_name) {
  const fs::path dir(dir_name);
  std::ifstream in(dir / "summary.json");
  if (!in) throw std::runtime_error("no summary.json in " + dir.string());
  const json s = json::parse(in);
  const auto objects = s.at("objects").get<std::vector<std::string>>();
  const auto actions = s.at("actions").get<std::vector<std::string>>();
  std::vector<std::string> systems;
  for (auto& [name, _] : s.at("systems").items()) systems.push_back(name);
  std::vector<std::string> written;
  const std::string title_base = s.value("experiment", std::string("experiment")) + ", " +
                                 std::to_string(s.value("steps", 0)) + " steps";

  // ---- final affordances: box plots (Figures 5, 10)
  {
    const fs::path csv = dir / "fig_affordances.csv", gp = dir / "fig_affordances.gp", png = dir / "fig_affordances.png";
    std::ofstream out(csv);
    out << "action,object,system,x,min,q1,median,q3,max,target\n";
    for (std::size_t a = 0; a < actions.size(); ++a)
      for (std::size_t i = 0; i < objects.size(); ++i)
        for (std::size_t k = 0; k < systems.size(); ++k) {
          const json& js = s["systems"][systems[k]];
          std::vector<double> v;
          for (const auto& r : js["runs"]) v.push_back(r["affordance"][i][a].get<double>());
          if (v.empty()) continue;
          const Box b = box(v);
          const double x = i + 1 + (static_cast<double>(k) - (systems.size() - 1) / 2.0) * 0.25;
          out << a << ",\"" << objects[i] << "\"," << systems[k] << "," << x << "," << b.min << "," << b.q1 << ","
              << b.median << "," << b.q3 << "," << b.max << "," << js["target"][i][a].get<double>() << "\n";
        }
    out.close();
    std::ofstream g(gp);
    g << "set terminal pngcairo size 1400,1000 font 'DejaVu Sans,10'\nset output " << quoted(png.string()) << "\n"
      << "set datafile separator ','\nset multiplot layout 2,2 title " << quoted("Final affordance predictions (" + title_base + "), box: quartiles, bars: min-max") << "\n"
      << "set yrange [-0.05:1.05]\nset xrange [0.4:" << objects.size() + 0.6 << "]\nset boxwidth 0.2\nset grid ytics\n"
      << "set key outside bottom center horizontal\n";
    g << "set xtics (";
    for (std::size_t i = 0; i < objects.size(); ++i) g << (i ? ", " : "") << quoted(objects[i]) << " " << i + 1;
    g << ") rotate by 30 right\n";
    for (std::size_t a = 0; a < actions.size(); ++a) {
      g << "set title " << quoted(actions[a]) << "\nplot ";
      for (std::size_t k = 0; k < systems.size(); ++k)
        g << (k ? ", " : "") << quoted(csv.string()) << " using ($1==" << a << " && strcol(3) eq " << quoted(systems[k])
          << " ? $4 : NaN):6:5:9:8 with candlesticks whiskerbars lc rgb '" << kSystemColour(systems[k])
          << "' fs solid 0.4 title " << quoted(systems[k]) << ", '' using ($1==" << a << " && strcol(3) eq "
          << quoted(systems[k]) << " ? $4 : NaN):7:7:7:7 with candlesticks lc rgb 'black' notitle";
      g << ", " << quoted(csv.string()) << " using ($1==" << a
        << " ? $4 : NaN):10 with points pt 1 ps 1.2 lc rgb 'black' title 'table'\n";
    }
    g << "unset multiplot\n";
    g.close();
    runGnuplot(gp);
    written.push_back(png.string());
  }

  // ---- learning curves (Figures 7-9)
  for (const auto& sys : systems) {
    const json& js = s["systems"][sys];
    if (!js.contains("curves")) continue;
    const fs::path csv = dir / ("fig_curves_" + sys + ".csv"), gp = dir / ("fig_curves_" + sys + ".gp"),
                   png = dir / ("fig_curves_" + sys + ".png");
    std::ofstream out(csv);
    out << "step";
    for (std::size_t a = 0; a < actions.size(); ++a)
      for (const auto& o : objects) out << ",\"" << actions[a] << ": " << o << "\"";
    out << "\n";
    const auto& steps = js["curves"]["steps"];
    for (std::size_t t = 0; t < steps.size(); ++t) {
      out << steps[t].get<long>();
      for (std::size_t a = 0; a < actions.size(); ++a)
        for (std::size_t i = 0; i < objects.size(); ++i) out << "," << js["curves"]["mean"][t][i][a].get<double>();
      out << "\n";
    }
    out.close();
    std::ofstream g(gp);
    g << "set terminal pngcairo size 1400,1000 font 'DejaVu Sans,10'\nset output " << quoted(png.string()) << "\n"
      << "set datafile separator ','\nset multiplot layout 2,2 title "
      << quoted(sys + ": mean affordance predictions over " + std::to_string(js["runs"].size()) + " run(s), " + title_base) << "\n"
      << "set yrange [-0.05:1.05]\nset grid\nset xlabel 'step'\nset key outside right\n";
    for (std::size_t a = 0; a < actions.size(); ++a) {
      g << "set title " << quoted(actions[a]) << "\nplot ";
      for (std::size_t i = 0; i < objects.size(); ++i)
        g << (i ? ", " : "") << quoted(csv.string()) << " using 1:" << 2 + a * objects.size() + i
          << " with linespoints pi 10 " << objectStyle(objects[i]) << " title " << quoted(objects[i]);
      g << "\n";
    }
    g << "unset multiplot\n";
    g.close();
    runGnuplot(gp);
    written.push_back(png.string());
  }

  // ---- completion steps (Figure 6)
  bool any_extrinsic = false;
  for (const auto& sys : systems) any_extrinsic |= s["systems"][sys].contains("extrinsic");
  if (any_extrinsic) {
    const fs::path csv = dir / "fig_completion.csv", gp = dir / "fig_completion.gp", png = dir / "fig_completion.png";
    std::ofstream out(csv);
    out << "system,sub_goals,x,n,min,q1,median,q3,max,fit_a,fit_b\n";
    double top = 1;
    for (std::size_t k = 0; k < systems.size(); ++k) {
      const json& js = s["systems"][systems[k]];
      if (!js.contains("extrinsic")) continue;
      const json& cs = js["extrinsic"]["completion_steps"];
      const double a = cs.contains("fit") ? cs["fit"]["a"].get<double>() : 0, b = cs.contains("fit") ? cs["fit"]["b"].get<double>() : 0;
      for (const auto& sc : js["extrinsic"]["scenarios"]) {
        const json& c = cs[sc.get<std::string>()];
        const int x = c["sub_goals"].get<int>();
        top = std::max(top, c["max"].get<double>());
        out << systems[k] << "," << x << "," << x + (static_cast<double>(k) - (systems.size() - 1) / 2.0) * 0.2 << ","
            << c["n"] << "," << c["min"] << "," << c["q1"] << "," << c["median"] << "," << c["q3"] << "," << c["max"]
            << "," << a << "," << b << "\n";
      }
    }
    out.close();
    std::ofstream g(gp);
    g << "set terminal pngcairo size 900,650 font 'DejaVu Sans,11'\nset output " << quoted(png.string()) << "\n"
      << "set datafile separator ','\nset title " << quoted("Completion steps of solved tests (" + title_base + ")") << "\n"
      << "set xlabel 'sub-goals (scenario)'\nset ylabel 'steps'\nset grid\nset boxwidth 0.15\nset key left top\n"
      << "set xrange [0.4:5.6]\nset yrange [0:" << top * 1.08 << "]\nplot ";
    bool first = true;
    for (std::size_t k = 0; k < systems.size(); ++k) {
      const json& js = s["systems"][systems[k]];
      if (!js.contains("extrinsic")) continue;
      const json& cs = js["extrinsic"]["completion_steps"];
      g << (first ? "" : ", ") << quoted(csv.string()) << " using (strcol(1) eq " << quoted(systems[k])
        << " ? $3 : NaN):6:5:9:8 with candlesticks whiskerbars lc rgb '" << kSystemColour(systems[k])
        << "' fs solid 0.4 title " << quoted(systems[k]) << ", '' using (strcol(1) eq " << quoted(systems[k])
        << " ? $3 : NaN):7:7:7:7 with candlesticks lc rgb 'black' notitle";
      if (cs.contains("fit")) {
        std::ostringstream f;
        f << cs["fit"]["a"].get<double>() << "*x**2 + (" << cs["fit"]["b"].get<double>() << ")*x";
        g << ", " << f.str() << " lc rgb '" << kSystemColour(systems[k]) << "' dt 2 title "
          << quoted(systems[k] + " fit");
      }
      first = false;
    }
    if (s.contains("reference_completion_fit"))
      g << ", " << s["reference_completion_fit"]["a"].get<double>() << "*x**2 + ("
        << s["reference_completion_fit"]["b"].get<double>() << ")*x lc rgb 'black' dt 3 title 'paper, IMP'";
    g << "\n";
    g.close();
    runGnuplot(gp);
    written.push_back(png.string());
  }
  return written;
}

}  // namespace afford
