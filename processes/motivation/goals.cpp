#include "motivation/goals.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "afford/components.hpp"
#include "afford/image.hpp"
#include "afford/rng.hpp"

namespace afford {

namespace {

ComponentRegistry<GoalChooser, GoalParams>& registry() {
  static ComponentRegistry<GoalChooser, GoalParams> r(
      "goals.kind", "motivation",
      {{"imgep", [](const GoalParams& p) { return std::make_unique<ImgepChooser>(p); }}});
  return r;
}

// Sub-draws of one goal's key (Purpose::GoalChoice, sub-key = goal id).
enum Draw : std::uint64_t { ExploreOrNot = 0, ModuleRandom = 1, ModulePick = 2, Candidate = 3, ExploreAction = 4 };

double mean(const std::deque<double>& h, std::size_t from, std::size_t to) {
  double sum = 0;
  for (std::size_t i = from; i < to; ++i) sum += h[i];
  return to > from ? sum / static_cast<double>(to - from) : 0.0;
}

// Whether a look shows an object under its gaze: the pixels that are not the
// black table centre within a quarter of the look's side of its middle. A look
// at an object, from a scan or top-down attention, is centred on it; a look at
// a place where no object stands (the remembered object has gone) shows at most
// the edge of a neighbour, far from the middle, and that is no object there.
bool centredObject(const std::vector<std::uint8_t>& image, int side) {
  if (side <= 0 || image.size() != 3 * static_cast<std::size_t>(side) * static_cast<std::size_t>(side)) return false;
  double sum_col = 0, sum_row = 0, n = 0;
  for (int row = 0; row < side; ++row)
    for (int col = 0; col < side; ++col) {
      const std::size_t i = 3 * (static_cast<std::size_t>(row) * static_cast<std::size_t>(side) + static_cast<std::size_t>(col));
      if (image[i] == 0 && image[i + 1] == 0 && image[i + 2] == 0) continue;
      sum_col += col;
      sum_row += row;
      n += 1;
    }
  if (n == 0) return false;
  const double middle = (side - 1) / 2.0;
  return std::max(std::abs(sum_col / n - middle), std::abs(sum_row / n - middle)) <= side / 4.0;
}

// The colour most of an object's pixels have (the table's camera draws each object in its flat colour; the
// table is black): its key, 0 for a look with no object.
std::uint32_t mainColour(const std::vector<std::uint8_t>& image) {
  std::map<std::uint32_t, int> count;
  for (std::size_t i = 0; i + 2 < image.size(); i += 3) {
    const std::uint32_t key = (std::uint32_t{image[i]} << 16) | (std::uint32_t{image[i + 1]} << 8) | image[i + 2];
    if (key != 0) ++count[key];
  }
  const auto most = std::max_element(count.begin(), count.end(),
                                     [](const auto& a, const auto& b) { return a.second < b.second; });
  return most == count.end() ? 0 : most->first;
}

// Metres at height z above the table, in scene units (the camera's width is one unit).
double sceneUnits(const table::CameraSpec& camera, double metres, double z) {
  return metres * camera.focalPx() / (camera.above - z) / std::max(1, camera.width);
}

}  // namespace

ObjectGeometry objectGeometry(const RunConfig& c) {
  if (c.world.kind != WorldKind::Table) return {0.75 * c.world.object_size, 0.5 * c.world.object_size};
  // Any object may lie or stand after an action: its reach is the sphere holding it, seen at the height of the
  // tallest top; two touching objects' centres are at least their narrowest half-extents apart, seen on the table.
  double reach = 0, narrowest = 0;
  for (const table::ObjectSpec& o : c.table.spec.objects) {
    double squares = 0;
    for (double h : o.size) squares += h * h;
    if (o.shape == table::Shape::Box) reach = std::max(reach, std::sqrt(squares));
    else if (o.shape == table::Shape::Cylinder) reach = std::max(reach, std::hypot(o.size.at(0), o.size.at(1)));
    else reach = std::max(reach, o.size.at(0));
    const double least = *std::min_element(o.size.begin(), o.size.end());
    narrowest = narrowest == 0 ? least : std::min(narrowest, least);
  }
  const table::CameraSpec& camera = c.table.spec.camera;
  return {sceneUnits(camera, reach, 2 * reach), sceneUnits(camera, 2 * narrowest, 0)};
}

Goal explorationGoal(std::int64_t seed, std::int64_t step, int id) {
  const KeyedRng rng(seed, step, Purpose::GoalChoice, static_cast<std::uint64_t>(id));
  Goal g;
  g.module = GoalModule::Explore;
  g.action = std::min(kNumActions - 1, static_cast<int>(rng.uniform(ExploreAction) * kNumActions));
  return g;
}

void registerGoalChooser(const std::string& kind, GoalChooserFactory factory) {
  registry().add(kind, std::move(factory));
}
std::vector<std::string> goalChooserKinds() { return registry().kinds(); }
std::unique_ptr<GoalChooser> makeGoalChooser(const GoalParams& params) {
  return registry().make(params, params.goals.kind);
}

// ---- competence ---------------------------------------------------------------

void Competence::attempted(GoalModule m, double competence) {
  auto& h = history_[static_cast<std::size_t>(m)];
  h.push_back(competence);
  while (h.size() > 2 * static_cast<std::size_t>(window_)) h.pop_front();
}

double Competence::progress(GoalModule m) const {
  const auto& h = history_[static_cast<std::size_t>(m)];
  if (h.size() < 2) return 0;
  const std::size_t half = h.size() / 2;
  return std::abs(mean(h, h.size() - half, h.size()) - mean(h, 0, half));
}

GoalModule Competence::choose(const std::array<bool, kGoalModules>& available, double random_share, double u,
                              double v) const {
  std::vector<GoalModule> open;
  double total = 0;
  for (int m = 0; m < kGoalModules; ++m)
    if (available[static_cast<std::size_t>(m)]) {
      open.push_back(static_cast<GoalModule>(m));
      total += progress(static_cast<GoalModule>(m));
    }
  if (open.empty()) return GoalModule::Explore;
  if (u < random_share || total <= 0) {
    const auto i = std::min(open.size() - 1, static_cast<std::size_t>(v * static_cast<double>(open.size())));
    return open[i];
  }
  double acc = 0;
  for (GoalModule m : open) {
    acc += progress(m) / total;
    if (v < acc) return m;
  }
  return open.back();
}

void Competence::save(SnapshotWriter& w) const {
  for (const auto& h : history_) w.doubles(std::vector<double>(h.begin(), h.end()));
}

void Competence::load(SnapshotReader& r) {
  for (auto& h : history_) {
    const std::int64_t n = r.within("competence attempts", 0, 2 * static_cast<std::int64_t>(window_));
    std::vector<double> v(static_cast<std::size_t>(n));
    r.bytes("competence", v.data(), v.size() * sizeof(double));
    h.assign(v.begin(), v.end());
  }
}

// ---- imgep --------------------------------------------------------------------

ImgepChooser::ImgepChooser(const GoalParams& params)
    : params_(params),
      table_(params.world.kind == WorldKind::Table),
      // The longest object's reach from its centre (the grid's rectangle, 1.5 sizes long: 0.75), a focus window
      // half its side; and one pixel more, as the environment's windows are whole pixels.
      clear_((params.geometry.reach > 0 ? params.geometry.reach : 0.75 * params.world.object_size) +
             (static_cast<double>(params.focus_side) / 2 + 1) / std::max(1, params.world.size_px)),
      competence_(params.goals.window) {}

bool ImgepChooser::samePlace(double ax, double ay, double bx, double by) const {
  return std::hypot(ax - bx, ay - by) <= params_.planner.position_match;
}

std::deque<Seen>::iterator ImgepChooser::objectAt(double x, double y) {
  return std::find_if(objects_.begin(), objects_.end(), [&](const Seen& o) { return samePlace(o.x, o.y, x, y); });
}

void ImgepChooser::remember(std::deque<Seen>& where, Seen s) {
  where.push_back(std::move(s));
  while (where.size() > static_cast<std::size_t>(params_.goals.memory)) where.pop_front();
}

bool ImgepChooser::freeAt(double x, double y, const Seen* except) const {
  return std::none_of(objects_.begin(), objects_.end(), [&](const Seen& o) {
    return &o != except && std::max(std::abs(o.x - x), std::abs(o.y - y)) < clear_;
  });
}

void ImgepChooser::sawObject(std::int64_t, const Seen& object) {
  if (auto it = objectAt(object.x, object.y); it != objects_.end()) objects_.erase(it);
  // A look that shows no object under its gaze (the table alone, or a neighbour's edge) says only that the
  // place is empty.
  if (!centredObject(object.image, params_.focus_side)) return;
  // An object here: one remembered closer than half an object's size has left unseen (every shape holds a disc
  // of a third of the size round its centre, so two objects never stand that close; late objects placed over
  // one another, world.late_overlap, the eye sees as one).
  const double apart = params_.geometry.apart > 0 ? params_.geometry.apart : 0.5 * params_.world.object_size;
  objects_.erase(std::remove_if(objects_.begin(), objects_.end(),
                                [&](const Seen& o) { return std::hypot(o.x - object.x, o.y - object.y) < apart; }),
                 objects_.end());
  remember(objects_, object);
}

void ImgepChooser::rememberPlace(double x, double y) {
  const bool known = std::any_of(places_.begin(), places_.end(), [&](const Seen& p) { return samePlace(p.x, p.y, x, y); });
  if (!known) remember(places_, Seen{{}, x, y});
}

void ImgepChooser::sawTableEffect(const SeenEffect& e) {
  if (auto it = objectAt(e.before.x, e.before.y); it != objects_.end()) objects_.erase(it);
  const bool placed = takesPlace(WorldKind::Table, e.action) && e.target_x >= 0 && e.target_y >= 0;
  if (placed) {  // at its place, as it looked
    sawObject(e.step, Seen{e.before.image, e.target_x, e.target_y});
    rememberPlace(e.target_x, e.target_y);
    rememberPlace(e.before.x, e.before.y);
    return;
  }
  // Toppled or rolled: as it looks now, where the scan found it; the place it left is free.
  sawObject(e.step, e.after);
  rememberPlace(e.before.x, e.before.y);
  // A new look (a rolled ball looks as it did): kept with the change of its centre, the goal of a look on another
  // object of its colour.
  if (!centredObject(e.after.image, params_.focus_side) ||
      imageDistance(e.before.image, e.after.image) < params_.planner.subgoal_match)
    return;
  rememberLook(Seen{e.after.image, e.after.x - e.before.x, e.after.y - e.before.y});
}

void ImgepChooser::rememberLook(Seen look) {
  const bool known = std::any_of(colours_.begin(), colours_.end(), [&](const Seen& c) {
    return imageDistance(c.image, look.image) < params_.planner.subgoal_match;
  });
  if (!known) remember(colours_, std::move(look));
}

bool ImgepChooser::fits(const Seen& o, const Seen& c) const {
  if (imageDistance(o.image, c.image) < params_.planner.subgoal_match) return false;  // the look it has
  if (!table_) return silhouetteDistance(o.image, c.image) == 0;
  // On the table (a look of an object of its colour: next() compares their colours), seen inside the scene.
  const Seen at = lookPlace(o, c);
  const double rows = static_cast<double>(params_.world.rows()) / std::max(1, params_.world.size_px);
  return at.x >= 0 && at.x <= 1 && at.y >= 0 && at.y <= rows;
}

Seen ImgepChooser::lookPlace(const Seen& o, const Seen& c) const {
  return table_ ? Seen{{}, o.x + c.x, o.y + c.y} : Seen{{}, o.x, o.y};
}

void ImgepChooser::sawEffect(const SeenEffect& e) {
  if (!e.affordance) return;  // nothing changed: the object is as it was seen
  if (table_) {
    sawTableEffect(e);
    return;
  }
  if (auto it = objectAt(e.before.x, e.before.y); it != objects_.end()) objects_.erase(it);
  // A move takes the object, as it looked, to its target; a colour change leaves it in place in its new colour.
  // (The change-driven scan's gaze may rest where the change was largest, the place a moved object left.)
  const bool moved = e.action == kMove && e.target_x >= 0 && e.target_y >= 0;
  sawObject(e.step, moved ? Seen{e.before.image, e.target_x, e.target_y} : Seen{e.after.image, e.before.x, e.before.y});
  if (e.action == kMove) {  // where it went, and where it stood: places an object can be moved to
    rememberPlace(e.target_x >= 0 ? e.target_x : e.after.x, e.target_y >= 0 ? e.target_y : e.after.y);
    rememberPlace(e.before.x, e.before.y);
    return;
  }
  imagined(Imagined{e.step, e.action, e.before.image, e.after.image, e.after.x, e.after.y});
}

void ImgepChooser::imagined(const Imagined& o) {
  // On the table the looks are those seen: a topple's direction is drawn, and its predicted window is an average
  // of the looks it left.
  if (table_) return;
  // A colour outcome: the object's silhouette in another colour (a prediction that is not one is left out).
  if (o.action == kMove || o.image.empty() || silhouetteDistance(o.object, o.image) != 0 ||
      imageDistance(o.object, o.image) < params_.planner.subgoal_match)
    return;
  rememberLook(Seen{o.image, o.x, o.y});
}

void ImgepChooser::attempted(const GoalAttempt& a) {
  // A goal of a place not reached after acting: the place may not be free (an object the agent has not seen
  // yet stands there, and the environment does not carry the move out): no more goals there until a move
  // reaches it.
  if ((a.module == GoalModule::Move || a.module == GoalModule::ColourPlace) && !a.reached && a.actions > 0)
    places_.erase(std::remove_if(places_.begin(), places_.end(),
                                 [&](const Seen& p) { return samePlace(p.x, p.y, last_x_, last_y_); }),
                  places_.end());
  // A goal found reached when set took no action: it says nothing of the agent's competence.
  if (a.module != GoalModule::Explore && !(a.reached && a.actions == 0))
    competence_.attempted(a.module, a.reached ? 1.0 : 0.0);
}

Goal ImgepChooser::next(std::int64_t step, int id) {
  const KeyedRng rng(params_.seed, step, Purpose::GoalChoice, static_cast<std::uint64_t>(id));
  const auto explore = [&] { return explorationGoal(params_.seed, step, id); };
  if (id < params_.goals.bootstrap || rng.uniform(ExploreOrNot) < params_.goals.explore_share) return explore();

  // The candidates of each module, on the objects as last seen: a colour the
  // object's silhouette took after a change (not the one it has), a free place
  // it is not at, or both.
  std::vector<std::pair<const Seen*, const Seen*>> colour;  // object, colour outcome
  const auto mains = [&](const std::deque<Seen>& seen) {  // (the table's looks fit by colour)
    std::vector<std::uint32_t> out;
    for (const Seen& x : seen) out.push_back(table_ ? mainColour(x.image) : 0);
    return out;
  };
  const std::vector<std::uint32_t> object_colours = mains(objects_), look_colours = mains(colours_);
  for (std::size_t i = 0; i < objects_.size(); ++i)
    for (std::size_t j = 0; j < colours_.size(); ++j)
      if (object_colours[i] == look_colours[j] && fits(objects_[i], colours_[j]))
        colour.emplace_back(&objects_[i], &colours_[j]);
  std::vector<std::pair<const Seen*, const Seen*>> move;  // object, place
  for (const Seen& o : objects_)
    for (const Seen& p : places_)
      if (std::max(std::abs(o.x - p.x), std::abs(o.y - p.y)) >= clear_ && freeAt(p.x, p.y, &o)) move.emplace_back(&o, &p);
  std::size_t both = 0;  // colour x places of the same object
  for (const auto& [o, c] : colour)
    for (const auto& [mo, p] : move) both += mo == o;
  const std::array<bool, kGoalModules> available = {false, !colour.empty(), !move.empty(), both > 0};
  const GoalModule m = competence_.choose(available, params_.goals.random_share, rng.uniform(ModuleRandom),
                                          rng.uniform(ModulePick));
  const double pick = rng.uniform(Candidate);
  const auto index = [&](std::size_t n) { return std::min(n - 1, static_cast<std::size_t>(pick * static_cast<double>(n))); };
  Goal g;
  g.module = m;
  // The goal: `image` at `place`, acting on `object`.
  const auto aim = [&](const Seen& object, const Seen& place, const std::vector<std::uint8_t>& image) {
    g.object_x = object.x;
    g.object_y = object.y;
    g.x = last_x_ = place.x;
    g.y = last_y_ = place.y;
    g.image = image;
    return g;
  };
  switch (m) {
    case GoalModule::Explore:
      return explore();
    case GoalModule::Colour: {
      const auto& [o, c] = colour[index(colour.size())];
      return aim(*o, lookPlace(*o, *c), c->image);
    }
    case GoalModule::Move: {
      const auto& [o, p] = move[index(move.size())];
      return aim(*o, *p, o->image);
    }
    case GoalModule::ColourPlace: {
      std::size_t k = index(both);
      for (const auto& [o, c] : colour)
        for (const auto& [mo, p] : move)
          if (mo == o && k-- == 0) return aim(*o, *p, c->image);
      break;
    }
  }
  return explore();
}

namespace {
void saveSeen(SnapshotWriter& w, const std::deque<Seen>& seen) {
  w.i64(static_cast<std::int64_t>(seen.size()));
  for (const Seen& s : seen) {
    w.blob(s.image);
    w.f64(s.x);
    w.f64(s.y);
  }
}
void loadSeen(SnapshotReader& r, std::deque<Seen>& seen, std::int64_t most, std::size_t image_bytes) {
  seen.clear();
  const std::int64_t n = r.within("seen", 0, most);
  for (std::int64_t i = 0; i < n; ++i) {
    Seen s;
    s.image = r.blob("seen image", image_bytes);
    s.x = r.f64("seen x");
    s.y = r.f64("seen y");
    seen.push_back(std::move(s));
  }
}
}  // namespace

void ImgepChooser::save(SnapshotWriter& w) const {
  w.f64(last_x_);
  w.f64(last_y_);
  competence_.save(w);
  saveSeen(w, objects_);
  saveSeen(w, colours_);
  saveSeen(w, places_);
}

void ImgepChooser::load(SnapshotReader& r) {
  last_x_ = r.f64("last goal x");
  last_y_ = r.f64("last goal y");
  competence_.load(r);
  const std::size_t bytes = 3 * static_cast<std::size_t>(params_.focus_side) * static_cast<std::size_t>(params_.focus_side);
  loadSeen(r, objects_, params_.goals.memory, bytes);
  loadSeen(r, colours_, params_.goals.memory, bytes);
  loadSeen(r, places_, params_.goals.memory, bytes);
}

}  // namespace afford
