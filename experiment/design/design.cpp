#include "experiment/design/design.hpp"
#include "experiment/design/experiment_file.hpp"

#include <gsl/gsl_cdf.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <stdexcept>

namespace afford {

std::string Condition::value(const std::string& key) const {
  for (const auto& [k, v] : settings)
    if (k == key) return v;
  return "";
}

std::vector<Condition> conditionsOf(const ExtrinsicDesign& d) {
  std::vector<Condition> out{Condition{}};
  for (const auto& [key, values] : d.vary) {
    std::vector<Condition> next;
    for (const Condition& c : out)
      for (const auto& v : values) {
        Condition n = c;
        n.settings.emplace_back(key, v);
        n.label += (n.label.empty() ? "" : " ") + key + "=" + v;
        next.push_back(n);
      }
    out = std::move(next);
  }
  return out;
}

namespace {

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / v.size();
}

double variance(const std::vector<double>& v) {  // sample variance
  if (v.size() < 2) return 0;
  const double m = mean(v);
  double s = 0;
  for (double x : v) s += (x - m) * (x - m);
  return s / (v.size() - 1);
}

Stats describe(const std::vector<double>& v) {
  std::vector<double> sorted = v;
  std::sort(sorted.begin(), sorted.end());
  return {static_cast<std::int64_t>(v.size()),
          mean(v),
          std::sqrt(variance(v)),
          quantile(sorted, 0.5),
          quantile(sorted, 0.25),
          quantile(sorted, 0.75),
          sorted.empty() ? 0.0 : sorted.front(),
          sorted.empty() ? 0.0 : sorted.back()};
}

// Samples of one system, scenario and condition: per test, and per agent (means).
struct Samples {
  std::vector<double> utility, checked_per_sub_goal, completion;
  int sub_goals = 0, objects = 0, multi_step = 0;
  std::map<std::size_t, std::vector<double>> agent_utility, agent_checked;
  int tests = 0, ok = 0, successes = 0;
};

Samples collect(const std::vector<TestRecord>& tests, const std::string& system, const std::string& scenario,
                int condition) {
  Samples s;
  for (const TestRecord& t : tests) {
    if (t.system != system || t.scenario != scenario || t.condition != condition) continue;
    ++s.tests;
    if (!t.ok) continue;  // failed on the infrastructure: not a result
    ++s.ok;
    s.successes += t.success;
    s.sub_goals = t.sub_goals;
    s.objects = t.objects;
    s.multi_step = t.multi_step;
    if (t.success) s.completion.push_back(t.completion);
    s.utility.push_back(t.utility);
    s.agent_utility[t.agent].push_back(t.utility);
    if (t.active_sub_goals > 0) {
      const double c = static_cast<double>(t.actions_checked) / t.active_sub_goals;
      s.checked_per_sub_goal.push_back(c);
      s.agent_checked[t.agent].push_back(c);
    }
  }
  return s;
}

std::vector<double> agentMeans(const std::map<std::size_t, std::vector<double>>& m) {
  std::vector<double> out;
  for (const auto& [agent, v] : m) out.push_back(mean(v));
  return out;
}

// The condition whose settings give `key`=`value` and, if `key2` is not
// empty, `key2`=`value2`; -1 if none.
int findCondition(const std::vector<Condition>& cs, const std::string& key, const std::string& value,
                  const std::string& key2 = "", const std::string& value2 = "") {
  for (std::size_t i = 0; i < cs.size(); ++i)
    if (cs[i].value(key) == value && (key2.empty() || cs[i].value(key2) == value2)) return static_cast<int>(i);
  return -1;
}

std::vector<std::string> valuesOf(const ExtrinsicDesign& d, const std::string& key) {
  for (const auto& [k, v] : d.vary)
    if (k == key) return v;
  throw std::runtime_error("extrinsic.analysis " + d.analysis + " needs extrinsic.vary." + key);
}

}  // namespace

double quantile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return 0;
  const double pos = q * (sorted.size() - 1);
  const std::size_t i = static_cast<std::size_t>(pos);
  const double f = pos - i;
  return i + 1 < sorted.size() ? sorted[i] * (1 - f) + sorted[i + 1] * f : sorted[i];
}

std::optional<QuadraticFit> fitCompletion(const std::vector<std::pair<double, double>>& points) {
  double sxx = 0, sxy = 0, sx3 = 0, sx4 = 0, sx2y = 0;  // normal equations of y = a x^2 + b x
  for (const auto& [x, y] : points) sxx += x * x, sx3 += x * x * x, sx4 += x * x * x * x, sxy += x * y, sx2y += x * x * y;
  const double det = sx4 * sxx - sx3 * sx3;
  if (std::abs(det) <= 1e-12 * std::max(1.0, sx4 * sxx)) return std::nullopt;
  return QuadraticFit{(sx2y * sxx - sxy * sx3) / det, (sx4 * sxy - sx3 * sx2y) / det};
}

WelchResult welchTest(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() < 2 || b.size() < 2) throw std::invalid_argument("Welch's t-test needs at least two values per sample");
  WelchResult r;
  r.mean_a = mean(a);
  r.mean_b = mean(b);
  const double va = variance(a) / a.size(), vb = variance(b) / b.size();
  if (va + vb == 0) {  // two constant samples
    r.t = 0;
    r.df = static_cast<double>(a.size() + b.size() - 2);
    r.p = r.mean_a == r.mean_b ? 1.0 : 0.0;
    return r;
  }
  r.t = (r.mean_a - r.mean_b) / std::sqrt(va + vb);
  r.df = (va + vb) * (va + vb) /
         ((va * va) / (a.size() - 1) + (vb * vb) / (b.size() - 1));  // Welch-Satterthwaite
  r.p = 2.0 * gsl_cdf_tdist_Q(std::abs(r.t), r.df);
  return r;
}

namespace {

// Per system, the conditions' statistics: per scenario and per design point.
void summariseConditions(Summary& summary, const std::vector<TestRecord>& tests, const std::vector<Condition>& conditions,
                         const std::vector<std::string>& systems, const std::vector<std::string>& scenarios) {
  for (const auto& sys : systems) {
    std::vector<PlannerCondition> list;
    for (std::size_t c = 0; c < conditions.size(); ++c) {
      PlannerCondition entry;
      entry.label = conditions[c].label;
      for (const auto& [k, v] : conditions[c].settings) entry.settings[k] = v;
      std::vector<std::pair<double, double>> solved;  // (sub-goals, completion) of every solved test
      struct Point {
        int tests = 0, ok = 0, successes = 0;
        std::vector<double> completion;
      };
      std::map<std::array<int, 3>, Point> points;  // by (sub-goals, objects, two-action sub-goals)
      for (const auto& sc : scenarios) {
        const Samples s = collect(tests, sys, sc, static_cast<int>(c));
        for (double y : s.completion) solved.emplace_back(s.sub_goals, y);
        Point& p = points[{s.sub_goals, s.objects, s.multi_step}];
        p.tests += s.tests;
        p.ok += s.ok;
        p.successes += s.successes;
        p.completion.insert(p.completion.end(), s.completion.begin(), s.completion.end());
        entry.scenarios[sc] = {s.tests,
                               s.ok,
                               s.ok ? static_cast<double>(s.successes) / s.ok : 0.0,
                               describe(s.utility),
                               agentMeans(s.agent_utility),
                               describe(s.checked_per_sub_goal),
                               agentMeans(s.agent_checked),
                               s.sub_goals,
                               s.objects,
                               s.multi_step,
                               describe(s.completion)};
      }
      for (const auto& [key, p] : points) {
        std::vector<double> per_sub_goal;
        for (double y : p.completion) per_sub_goal.push_back(y / key[0]);
        entry.points.push_back({key[0], key[1], key[2], p.tests, p.ok,
                                p.ok ? static_cast<double>(p.successes) / p.ok : 0.0, describe(p.completion),
                                describe(per_sub_goal)});
      }
      if (const auto fit = fitCompletion(solved)) entry.completion_fit = Fit{fit->a, fit->b};
      list.push_back(entry);
    }
    auto& ex = summary.systems[sys].extrinsic;
    (ex ? *ex : ex.emplace()).conditions = list;
  }
}

bool has(const std::vector<std::string>& systems, const std::string& s) {
  return std::find(systems.begin(), systems.end(), s) != systems.end();
}

// Figure 12: goal vs utility planner per action budget.
UtilityAnalysis analyseUtility(const std::vector<TestRecord>& tests, const std::vector<Condition>& conditions,
                    const ExtrinsicDesign& design, const std::vector<std::string>& systems, const std::string& sc) {
  const std::string sys = has(systems, "IMP") ? "IMP" : systems.front();
  UtilityAnalysis u;
  u.system = sys;
  u.scenario = sc;
  for (const auto& b : valuesOf(design, "planner.max_attempts")) {
    const int cg = findCondition(conditions, "planner.kind", "goal", "planner.max_attempts", b);
    const int cu = findCondition(conditions, "planner.kind", "utility", "planner.max_attempts", b);
    if (cg < 0 || cu < 0) throw std::runtime_error("extrinsic.analysis utility needs planner.kind goal and utility");
    const Samples g = collect(tests, sys, sc, cg), ut = collect(tests, sys, sc, cu);
    u.budgets.push_back(std::stoi(b));
    u.goal_mean.push_back(mean(g.utility));
    u.utility_mean.push_back(mean(ut.utility));
    u.goal_sd.push_back(std::sqrt(variance(g.utility)));
    u.utility_sd.push_back(std::sqrt(variance(ut.utility)));
    const bool testable = g.utility.size() >= 2 && ut.utility.size() >= 2;
    const WelchResult w = testable ? welchTest(ut.utility, g.utility) : WelchResult{};
    u.p_values.push_back(testable ? Nullable<double>(w.p) : Nullable<double>());
    u.t.push_back(testable ? Nullable<double>(w.t) : Nullable<double>());
    u.n.push_back({static_cast<std::int64_t>(g.utility.size()), static_cast<std::int64_t>(ut.utility.size())});
  }
  return u;
}

// Figure 13: systems per action budget (their means and deviations go into each system's summary).
ForwardModelsAnalysis analyseForwardModels(Summary& summary, const std::vector<TestRecord>& tests, const std::vector<Condition>& conditions,
                          const ExtrinsicDesign& design, const std::vector<std::string>& systems, const std::string& sc) {
  const auto budgets = valuesOf(design, "planner.max_attempts");
  ForwardModelsAnalysis fm;
  fm.scenario = sc;
  for (const auto& b : budgets) fm.budgets.push_back(std::stoi(b));
  std::map<std::string, std::vector<std::vector<double>>> samples;  // system -> per budget
  for (const auto& sys : systems) {
    std::vector<double> means, sds;
    for (const auto& b : budgets) {
      const int c = findCondition(conditions, "planner.max_attempts", b);
      const Samples s = collect(tests, sys, sc, c);
      samples[sys].push_back(s.utility);
      means.push_back(mean(s.utility));
      sds.push_back(std::sqrt(variance(s.utility)));
    }
    summary.systems[sys].utility_mean = means;
    summary.systems[sys].utility_sd = sds;
  }
  if (has(systems, "IMP"))
    for (const auto& other : systems) {
      if (other == "IMP") continue;
      const std::string pair = "IMP-" + other;
      PValues& p_values = fm.p_values[pair];
      PValues& t = fm.t[pair];
      for (std::size_t k = 0; k < budgets.size(); ++k) {
        const auto &a = samples["IMP"][k], &bb = samples[other][k];
        const bool testable = a.size() >= 2 && bb.size() >= 2;
        const WelchResult w = testable ? welchTest(a, bb) : WelchResult{};
        p_values.push_back(testable ? Nullable<double>(w.p) : Nullable<double>());
        t.push_back(testable ? Nullable<double>(w.t) : Nullable<double>());
      }
    }
  return fm;
}

// Figure 14: actions checked per sub-goal, with and without the affordance restriction.
SearchAnalysis analyseSearch(const std::vector<TestRecord>& tests, const std::vector<Condition>& conditions,
                   const std::vector<std::string>& systems, const std::string& sc) {
  const std::string sys = has(systems, "IMP") ? "IMP" : systems.front();
  const int cr = findCondition(conditions, "planner.restrict_by_affordance", "true");
  const int cu = findCondition(conditions, "planner.restrict_by_affordance", "false");
  if (cr < 0 || cu < 0)
    throw std::runtime_error("extrinsic.analysis search-reduction needs planner.restrict_by_affordance true and false");
  const Samples r = collect(tests, sys, sc, cr), u = collect(tests, sys, sc, cu);
  SearchAnalysis s;
  s.system = sys;
  s.scenario = sc;
  s.restricted_mean = mean(r.checked_per_sub_goal);
  s.unrestricted_mean = mean(u.checked_per_sub_goal);
  s.restricted_sd = std::sqrt(variance(r.checked_per_sub_goal));
  s.unrestricted_sd = std::sqrt(variance(u.checked_per_sub_goal));
  s.n = {static_cast<std::int64_t>(r.checked_per_sub_goal.size()), static_cast<std::int64_t>(u.checked_per_sub_goal.size())};
  const bool testable = r.checked_per_sub_goal.size() >= 2 && u.checked_per_sub_goal.size() >= 2;
  const WelchResult w = testable ? welchTest(r.checked_per_sub_goal, u.checked_per_sub_goal) : WelchResult{};
  if (testable) {
    s.p_value = w.p;
    s.t = w.t;
    s.df = w.df;
  }
  return s;
}

}  // namespace

void summariseDesign(Summary& summary, const std::vector<TestRecord>& tests, const std::vector<Condition>& conditions,
                     const ExtrinsicDesign& design, const std::vector<std::string>& systems,
                     const std::vector<std::string>& scenarios) {
  summariseConditions(summary, tests, conditions, systems, scenarios);
  if (design.analysis.empty()) return;
  const std::string& sc = scenarios.front();
  if (design.analysis == "utility")
    summary.utility = analyseUtility(tests, conditions, design, systems, sc);
  else if (design.analysis == "forward-models")
    summary.forward_models = analyseForwardModels(summary, tests, conditions, design, systems, sc);
  else if (design.analysis == "search-reduction")
    summary.search = analyseSearch(tests, conditions, systems, sc);
}

}  // namespace afford
