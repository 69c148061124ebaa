#include "motivation/goal_inputs.hpp"

#include <algorithm>
#include <climits>
#include <tuple>

namespace afford {

void GoalInputs::object(std::int64_t step, std::int32_t seq, Seen seen) {
  Entry e;
  e.step = step;
  e.kind = Object;
  e.seq = seq;
  e.seen = std::move(seen);
  add(std::move(e));
}

void GoalInputs::effect(SeenEffect effect) {
  Entry e;
  e.step = effect.step;
  e.kind = Effect;
  e.effect = std::move(effect);
  add(std::move(e));
}

void GoalInputs::forward(std::int64_t step, std::int32_t seq, std::vector<Imagined> outcomes) {
  Entry e;
  e.step = step;
  e.kind = Forward;
  e.seq = seq;
  e.imagined = std::move(outcomes);
  add(std::move(e));
}

void GoalInputs::add(Entry e) {
  ++held_[static_cast<std::size_t>(e.kind)];
  pending_.push_back(std::move(e));
}

void GoalInputs::feed(GoalChooser& chooser, std::int64_t step, std::int32_t seq) {
  // Before the goal's end: the answers to requests up to its seq, and the effects of the steps before its step.
  const auto before = [&](const Entry& e) { return e.kind == Effect ? e.step < step : e.seq <= seq; };
  std::vector<Entry> now;
  auto split = std::stable_partition(pending_.begin(), pending_.end(), [&](const Entry& e) { return !before(e); });
  std::move(split, pending_.end(), std::back_inserter(now));
  pending_.erase(split, pending_.end());
  for (const Entry& e : now) --held_[static_cast<std::size_t>(e.kind)];
  std::sort(now.begin(), now.end(), [](const Entry& a, const Entry& b) {
    const auto key = [](const Entry& e) { return std::make_tuple(e.step, e.kind == Effect ? 1 : 0, e.seq); };
    return key(a) < key(b);
  });
  for (Entry& e : now) {
    switch (e.kind) {
      case Object:
        chooser.sawObject(e.step, e.seen);
        objects_[e.step] = std::move(e.seen);
        break;
      case Forward: {
        const auto it = objects_.find(e.step);
        if (it == objects_.end()) break;  // (a query comes after its object: not from the planner)
        for (Imagined& o : e.imagined) {
          o.object = it->second.image;
          chooser.imagined(o);
        }
        break;
      }
      case Effect: {
        const auto it = objects_.find(e.step);
        if (it == objects_.end()) break;
        e.effect.before = it->second;
        chooser.sawEffect(e.effect);
        break;
      }
    }
  }
  // No effect or prediction of an earlier step is to come.
  objects_.erase(objects_.begin(), objects_.lower_bound(step));
}

void GoalInputs::clear() {
  pending_.clear();
  held_ = {};
  objects_.clear();
}

namespace {
void saveSeen(SnapshotWriter& w, const Seen& s) {
  w.blob(s.image);
  w.f64(s.x);
  w.f64(s.y);
}
Seen loadSeen(SnapshotReader& r, std::size_t image_bytes) {
  Seen s;
  s.image = r.blob("image", image_bytes);
  s.x = r.f64("x");
  s.y = r.f64("y");
  return s;
}
}  // namespace

void GoalInputs::save(SnapshotWriter& w) const {
  w.i64(static_cast<std::int64_t>(pending_.size()));
  for (const Entry& e : pending_) {
    w.i64(e.step);
    w.i64(e.kind);
    w.i64(e.seq);
    switch (e.kind) {
      case Object:
        saveSeen(w, e.seen);
        break;
      case Forward:
        w.i64(static_cast<std::int64_t>(e.imagined.size()));
        for (const Imagined& o : e.imagined) {
          w.i64(o.action);
          saveSeen(w, Seen{o.image, o.x, o.y});
        }
        break;
      case Effect:
        w.i64(e.effect.action);
        saveSeen(w, e.effect.after);
        w.f64(e.effect.target_x);
        w.f64(e.effect.target_y);
        w.i64(e.effect.affordance ? 1 : 0);
        break;
    }
  }
  w.i64(static_cast<std::int64_t>(objects_.size()));
  for (const auto& [step, seen] : objects_) {
    w.i64(step);
    saveSeen(w, seen);
  }
}

void GoalInputs::load(SnapshotReader& r, std::int64_t steps, std::size_t image_bytes, std::size_t most) {
  clear();
  const std::int64_t n = r.within("goal inputs held", 0, static_cast<std::int64_t>(most));
  for (std::int64_t i = 0; i < n; ++i) {
    Entry e;
    e.step = r.within("input step", 0, steps);
    e.kind = static_cast<Kind>(r.within("input kind", Object, Effect));
    e.seq = static_cast<std::int32_t>(r.within("input seq", 0, INT32_MAX));
    switch (e.kind) {
      case Object:
        e.seen = loadSeen(r, image_bytes);
        break;
      case Forward: {
        const std::int64_t k = r.within("predictions", 0, 64);
        for (std::int64_t j = 0; j < k; ++j) {
          Imagined o;
          o.step = e.step;
          o.action = static_cast<int>(r.within("prediction action", 0, 3));
          const Seen s = loadSeen(r, image_bytes);
          o.image = s.image;
          o.x = s.x;
          o.y = s.y;
          e.imagined.push_back(std::move(o));
        }
        break;
      }
      case Effect:
        e.effect.step = e.step;
        e.effect.action = static_cast<int>(r.within("effect action", 0, 3));
        e.effect.after = loadSeen(r, image_bytes);
        e.effect.target_x = r.f64("effect target x");
        e.effect.target_y = r.f64("effect target y");
        e.effect.affordance = r.within("effect held", 0, 1) == 1;
        break;
    }
    add(std::move(e));
  }
  const std::int64_t objects = r.within("objects held", 0, static_cast<std::int64_t>(most));
  for (std::int64_t i = 0; i < objects; ++i) {
    const std::int64_t step = r.within("object step", 0, steps);
    objects_[step] = loadSeen(r, image_bytes);
  }
}

}  // namespace afford
