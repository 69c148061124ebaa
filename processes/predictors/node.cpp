#include "predictors/node.hpp"

#include "predictors/messages.hpp"

#include "afford/affordance_table_t.hpp"
#include "afford/protocol.hpp"
#include "afford/names.hpp"
#include "afford/prediction_t.hpp"
#include "afford/decode.hpp"
#include "afford/run_result_t.hpp"

#include <climits>
#include <limits>

namespace afford {

namespace {
// A FOCUS of an object the predictors predict for: a scene scan or an attended object.
bool isObject(const focus_t& m) { return m.kind == focus_t::SCENE_SCAN || m.kind == focus_t::SCENE_OBJECT; }
}  // namespace

void PredictorsNode::Requests::save(SnapshotWriter& w) const {
  w.i64(done_);
  w.i64(static_cast<std::int64_t>(ahead_.size()));
  for (std::int32_t s : ahead_) w.i64(s);
}

void PredictorsNode::Requests::load(SnapshotReader& r) {
  done_ = static_cast<std::int32_t>(r.within("requests answered", 0, INT32_MAX));
  ahead_.clear();
  const std::int64_t n = r.within("requests answered ahead", 0, static_cast<std::int64_t>(kMostAhead));
  for (std::int64_t i = 0; i < n; ++i) ahead_.insert(static_cast<std::int32_t>(r.within("request", done_ + 1, INT32_MAX)));
}

PredictorsNode::PredictorsNode(lcm::LCM& lcm, std::shared_ptr<spdlog::logger> log, const ProtocolConfig& protocol,
                               bool async_effects, std::string checkpoint_root)
    : NodeBase(lcm, "predictors", std::move(log), protocol),
      async_effects_(async_effects),
      checkpoint_root_(std::move(checkpoint_root)) {
  takes(ch::probe, "the PROBE once (each object's focus image alone: the affordance tables are computed on them)")
      .refuse([this](const object_probe_t&) { return probes_.empty() ? "" : "the probe was received already"; })
      .then([this](const object_probe_t& m) { probes_ = m.images; });
  takes(ch::focus,
        "the FOCUS of a scene scan or an attended object (not a look at the goal or at a place); intrinsic "
        "phase: of each step in step order, once the step before is decided and, if it acted, learned from, "
        "and the probe is in (paper Algorithm 1); extrinsic phase: each, from the current iteration on; goals "
        "phase: every FOCUS in order (each answers a request of the planner, which it counts), an object's as in "
        "the intrinsic phase once every request before it is answered")
      .in(Phase::Goals)
      .refuse([this](const focus_t& m) {
        return isObject(m) && m.step >= config().steps ? "step " + std::to_string(m.step) + " is beyond the run's last step"
               : isObject(m) && m.step <= current_
                   ? "step " + std::to_string(m.step) + " is in the past (the next is " + std::to_string(current_ + 1) + ")"
                   : std::string();
      })
      .waitFor([this](const focus_t& m) {
        return !isObject(m) || (m.step == current_ + 1 && !probes_.empty() && requests_.before(m.seq) &&
                                (current_ < 0 || outcome_ == Outcome::Passed || outcome_ == Outcome::Learned));
      })
      .then([this](const focus_t& m) {
        requests_.answered(m.seq);
        if (isObject(m)) handleFocus(m);
      })
      .in({Phase::Intrinsic, Phase::Extrinsic})
      .ignoreIf([](const focus_t& m) { return !isObject(m); })
      .in(Phase::Intrinsic)
      .withinRun([this] { return config().steps; })
      .stepInOrder([this] { return current_ + 1; })
      .waitFor([this](const focus_t&) {
        return !probes_.empty() && (current_ < 0 || outcome_ == Outcome::Passed || outcome_ == Outcome::Learned);
      })
      .then([this](const focus_t& m) { handleFocus(m); })
      .in(Phase::Extrinsic)
      .refuse([this](const focus_t& m) {
        return m.step < current_ ? "step " + std::to_string(m.step) + " is in the past" : std::string();
      })
      .then([this](const focus_t& m) {
        current_ = m.step;
        handled(m.step);
        publishPrediction(m);
      });
  takes(ch::decision,
        "intrinsic phase: the DECISION of the step whose FOCUS was taken last, once: an action awaits its "
        "EFFECT, a pass ends the step; goals phase: as in the intrinsic phase, once every request of the planner "
        "before it is answered")
      .in(Phase::Goals)
      .waitFor([this](const decision_t& m) { return requests_.before(m.seq + 1); })
      .in({Phase::Intrinsic, Phase::Goals})
      .refuse([this](const decision_t& m) {
        return m.step < current_ || (m.step == current_ && outcome_ != Outcome::Unknown)
                   ? "step " + std::to_string(m.step) + " is already decided (now at " + std::to_string(current_) + ")"
                   : std::string();
      })
      .waitFor([this](const decision_t& m) { return m.step == current_; })
      .then([this](const decision_t& m) { decided(m); });
  takes(ch::effect,
        "intrinsic phase: the EFFECT of the step whose action was decided last, once, of that action: the "
        "predictors learn from it (paper 2.3.3)")
      .in({Phase::Intrinsic, Phase::Goals})
      .refuse([this](const effect_t& m) {
        return m.step < current_ || (m.step == current_ && outcome_ == Outcome::Learned)
                   ? "step " + std::to_string(m.step) + " is in the past (already learned)"
                   : std::string();
      })
      .refuse([this](const effect_t& m) {
        return m.step == current_ && outcome_ == Outcome::Passed
                   ? "no action was decided at step " + std::to_string(m.step)
                   : std::string();
      })
      .waitFor([this](const effect_t& m) { return m.step == current_ && outcome_ == Outcome::AwaitingEffect; })
      .refuse([this](const effect_t& m) {
        return m.action != action_ ? "action " + std::to_string(m.action) + " differs from the decided action " +
                                         std::to_string(action_)
                                   : std::string();
      })
      .then([this](const effect_t& m) { learn(m); })
      .in(Phase::Extrinsic)
      .refuse([](const effect_t&) { return "no learning in the extrinsic phase"; });
  takeQueries();
}

void PredictorsNode::takeQueries() {
  takes(ch::forwardQuery,
        "extrinsic phase: each FORWARD_QUERY once, in request order, with an agent loaded: what each action "
        "would do to the object; goals phase: each of the current step, before its DECISION, with the forward "
        "models as they have learned so far")
      .in(Phase::Intrinsic)
      .refuse([](const forward_query_t&) { return "no forward queries in the intrinsic phase"; })
      .in(Phase::Goals)
      .refuse([this](const forward_query_t& q) {
        return q.seq <= last_query_ ? "query " + std::to_string(q.seq) + " was answered already" : std::string();
      })
      .refuse([this](const forward_query_t& q) {
        return q.step < current_ ? "step " + std::to_string(q.step) + " is in the past" : std::string();
      })
      .waitFor([this](const forward_query_t& q) {
        return q.step == current_ && outcome_ == Outcome::Unknown && requests_.before(q.seq);
      })
      .then([this](const forward_query_t& q) {
        answer(q);
        requests_.answered(q.seq);
      })
      .in(Phase::Extrinsic)
      .refuse([this](const forward_query_t& q) {
        return q.seq <= last_query_ ? "query " + std::to_string(q.seq) + " was answered already" : std::string();
      })
      .refuse([this](const forward_query_t&) { return loaded_ ? "" : "no agent is loaded"; })
      .then([this](const forward_query_t& q) { answer(q); });
}

void PredictorsNode::checkCheckpointPath(const RunConfig& config) const {
  namespace fs = std::filesystem;
  const std::string where = "this process's checkpoint folder '" + checkpoint_root_ + "' (--checkpoint-dir)";
  // A checkpoint in another folder: the run's log root is not this process's --checkpoint-dir.
  const auto elsewhere = [&](const std::string& key, const fs::path& file, const std::string& verb) {
    return ConfigError(key + ": the run " + verb + " '" + printable(file.string()) + "', outside " + where +
                           ": start afford-predictors with --checkpoint-dir set to the runner's --log-root (here "
                           "probably '" + printable(file.parent_path().parent_path().string()) +
                           "'); a run's configuration does not choose where the predictors read or write",
                       key);
  };
  if (config.phase == Phase::Extrinsic) {
    const fs::path file = config.extrinsic_checkpoint;
    std::error_code ec;
    if (!insideFolder(file, checkpoint_root_)) throw elsewhere("extrinsic.checkpoint", file, "loads its agent from");
    if (!fs::is_regular_file(file, ec)) throw ConfigError("extrinsic.checkpoint: '" + printable(file.string()) + "' is not a file");
    return;
  }
  if (config.checkpoint.empty()) return;
  const fs::path file = config.checkpoint;
  const fs::path own = fs::path(checkpoint_root_) / runId();
  std::error_code ec;
  if (!insideFolder(file, checkpoint_root_)) throw elsewhere("run.checkpoint", file, "writes its checkpoint to");
  const bool in_own = fs::weakly_canonical(fs::absolute(file.parent_path(), ec), ec) ==
                      fs::weakly_canonical(fs::absolute(own, ec), ec);
  if (!in_own || file.extension() != ".ckpt")
    throw ConfigError("run.checkpoint: '" + printable(file.string()) + "' is " +
                          (in_own ? "not a .ckpt file" : "not in the run's own folder " + own.string() + "/") +
                          ": the predictors write only <run-id>/*.ckpt in " + where +
                          "; a run's configuration does not choose where",
                      "run.checkpoint");
}

void PredictorsNode::onConfigured(const RunConfig& config) {
  checkCheckpointPath(config);
  trainer_.reset();
  if (config.phase == Phase::Extrinsic) {
    namespace fs = std::filesystem;
    const std::string& path = config.extrinsic_checkpoint;
    std::error_code ec;
    const auto size = fs::file_size(path, ec);
    const auto mtime = fs::last_write_time(path, ec);
    if (!ec && loaded_ && loaded_->path == path && loaded_->size == size && loaded_->mtime == mtime) {
      core_ = loaded_->core;
    } else {
      core_ = std::make_shared<Predictors>(config);
      core_->load(path);  // throws: the config is refused, naming the file
      loaded_ = Loaded{path, size, mtime, core_, {}};
    }
  } else {
    loaded_.reset();
    // Never overwrite what an earlier run of this id saved (a replayed log on a live bus, a reused id). One this
    // very process saved for another request of the run id (taken from a recording played back, or from another
    // runner, and then left) is set aside, so that the request asked for now runs. (What was saved for other run
    // ids is forgotten: the map holds one run's files.)
    for (auto it = saved_.begin(); it != saved_.end();)
      it = std::filesystem::path(it->first).parent_path().filename() == runId() ? std::next(it) : saved_.erase(it);
    for (const std::string& file : {config.checkpoint, config.checkpoint_after_actions > 0
                                                           ? actionsCheckpoint(config.checkpoint, config.checkpoint_after_actions)
                                                           : std::string()}) {
      if (file.empty() || !std::filesystem::exists(file)) continue;
      const auto mine = saved_.find(file);
      if (mine == saved_.end() || mine->second == runConfigMessage().digest)
        throw ConfigError("checkpoint " + file + " exists already: run '" + runId() +
                          "' has been run before, and its weights are not overwritten");
      std::string aside;
      for (int k = 1; std::filesystem::exists(aside = file + ".other-request-" + std::to_string(k)); ++k) {
      }
      std::filesystem::rename(file, aside);
      saved_.erase(mine);
      log_->warn("run '{}': {}, which this process saved for another request of the run, set aside as {}", runId(),
                 file, aside);
    }
    core_ = std::make_shared<Predictors>(config);
  }
  if (async_effects_ && learning(config.phase)) trainer_ = std::make_unique<EffectTrainer>(*core_);
  last_query_ = -1;
  requests_.clear();
  probes_.clear();
  pending_trained_.reset();
  pending_effects_.clear();
  look_ = -1;
  revisits_ = 0;
  current_ = -1;
  outcome_ = Outcome::Unknown;
  finished_ = false;
}

void PredictorsNode::onStop() {
  trainer_.reset();
  core_.reset();
}

void PredictorsNode::handleFocus(const focus_t& m) {
  if (m.step % config().curve_interval == 0) publishTable(m.step);
  const Prediction p = publishPrediction(m);
  trainPendingEffects();  // off the critical path: the next decision is under way
  if (trainer_ && config().phase == Phase::Goals && m.kind == focus_t::SCENE_OBJECT) {
    // The planner's next request is a query about this object for the actions it affords (planner.cpp,
    // objectSeen): their outputs are made on the worker while the PREDICTION travels and the query comes back.
    const PlannerConfig& planner = config().planner;
    std::vector<int> actions;
    for (int a = 0; a < kNumActions; ++a)
      if (!planner.restrict_by_affordance || p.affordance[static_cast<std::size_t>(a)] > planner.affordance_threshold)
        actions.push_back(a);
    trainer_->ahead(std::move(actions), m.image);
  }
  current_ = m.step;
  focus_ = m;
  outcome_ = Outcome::Unknown;
  action_ = -1;
  handled(m.step);
}

Prediction PredictorsNode::publishPrediction(const focus_t& m) {
  // Intrinsic phase: the focus of step m.step, seen once (a memory remembers its look).
  const Prediction p = extrinsic() ? core_->predict(m.image) : core_->see(m.image, m.step);
  if (!extrinsic()) look_ = p.look;
  publish(ch::prediction, predictionMessage(runId(), m, p, pending_trained_));  // with the update since the last
  pending_trained_.reset();
  return p;
}

void PredictorsNode::answer(const forward_query_t& q) {
  last_query_ = q.seq;
  forward_prediction_t out;
  out.run_id = runId();
  out.step = q.step;
  out.seq = q.seq;
  out.n_actions = q.n_actions;
  out.actions = q.actions;
  out.size = q.size;
  if (!loaded_) {  // goals phase: the forward models as they stand, every update before this step applied
    trainPendingEffects();
    if (trainer_) trainer_->drain();
  }
  for (int a : q.actions) {
    if (!loaded_) {
      const std::vector<double> what = core_->whatEffect(a, q.image);
      out.what.emplace_back(what.begin(), what.end());
      const auto where = core_->whereEffect(a, q.x, q.y, q.target_x, q.target_y);
      out.where_x.push_back(where[0]);
      out.where_y.push_back(where[1]);
      continue;
    }
    // Extrinsic: core_ is loaded_->core, whose weights stay as loaded.
    auto key = std::make_pair(a, q.image);
    auto it = loaded_->what.find(key);
    if (it == loaded_->what.end()) {
      if (loaded_->what.size() >= kWhatKept) loaded_->what.clear();
      it = loaded_->what.emplace(std::move(key), core_->whatEffect(a, q.image)).first;
    }
    out.what.emplace_back(it->second.begin(), it->second.end());
    const auto where = core_->whereEffect(a, q.x, q.y, q.target_x, q.target_y);
    out.where_x.push_back(where[0]);
    out.where_y.push_back(where[1]);
  }
  if (q.n_prefix > 0) {  // an imagined object: what it would afford next (multi-step search)
    const Prediction p = core_->predict(q.image);
    out.input_affordance.assign(p.affordance.begin(), p.affordance.end());
  }
  out.n_input = static_cast<int8_t>(out.input_affordance.size());
  publish(ch::forwardPrediction, out);
  handled(q.step);
}

void PredictorsNode::decided(const decision_t& m) {
  if (m.acted) {
    outcome_ = Outcome::AwaitingEffect;
    action_ = m.action;
    revisits_ += m.revisit ? 1 : 0;
    return;
  }
  outcome_ = Outcome::Passed;
  for (auto& u : core_->replay(m.step)) pending_effects_.push_back(std::move(u));  // a step without an action replays too
  if (m.step == config().steps - 1) finish();
}

void PredictorsNode::learn(const effect_t& m) {
  TrainingReport r = core_->trainAffordance(experienceOf(focus_, m), m.step, look_);
  pending_trained_ = trainedMessage(runId(), m.step, r);
  pending_effects_ = std::move(r.effect_updates);
  // Goals phase: the next query waits for these updates; begun now, they are made while the next goal is set.
  if (config().phase == Phase::Goals) trainPendingEffects();
  outcome_ = Outcome::Learned;
  saveActionsCheckpoint();
  if (m.step == config().steps - 1) finish();
}

void PredictorsNode::trainPendingEffects() {
  if (pending_effects_.empty()) return;
  if (trainer_)
    trainer_->push(std::move(pending_effects_));
  else
    core_->trainEffects(pending_effects_);
  pending_effects_.clear();
}

void PredictorsNode::saveActionsCheckpoint() {
  const std::int64_t n = config().checkpoint_after_actions;
  if (n <= 0 || config().checkpoint.empty()) return;
  std::int64_t executed = 0;
  for (auto k : core_->executed()) executed += k;
  if (executed != n) return;
  trainPendingEffects();
  if (trainer_) trainer_->drain();  // the forward models have learned from all n actions
  const std::string file = actionsCheckpoint(config().checkpoint, n);
  try {
    core_->save(file);
    saved_[file] = runConfigMessage().digest;
    log_->info("run '{}': weights after {} actions saved to {}", runId(), n, file);
  } catch (const std::exception& e) {
    log_->error("{}", e.what());
  }
}

void PredictorsNode::publishTable(std::int64_t step) {
  affordance_table_t t{};
  t.run_id = runId();
  t.step = step;
  t.n_actions = kNumActions;
  for (const auto& row : core_->table(probes_)) t.affordance.emplace_back(row.begin(), row.end());
  t.n_objects = static_cast<int32_t>(t.affordance.size());
  publish(ch::affordanceTable, t);
}

void PredictorsNode::finish() {
  if (finished_) return;
  finished_ = true;
  trainPendingEffects();
  if (trainer_) trainer_->drain();  // every update applied before the checksum
  publishTable(config().steps);
  run_result_t r;
  r.run_id = runId();
  r.step = config().steps;
  r.weights_checksum = core_->weightsChecksum();
  r.checkpoint = config().checkpoint;
  if (!r.checkpoint.empty()) {
    try {
      core_->save(r.checkpoint, r.weights_checksum);
      saved_[r.checkpoint] = runConfigMessage().digest;
    } catch (const std::exception& e) {
      log_->error("{}", e.what());
      r.checkpoint.clear();
    }
  }
  r.n_actions = kNumActions;
  r.actions_executed.assign(core_->executed().begin(), core_->executed().end());
  r.successes.assign(core_->successes().begin(), core_->successes().end());
  r.looks = core_->memory() ? core_->memory()->looks() : 0;
  r.replayed = core_->replayedUpdates();
  r.replayed_effects = core_->replayedEffectUpdates();
  r.revisits = revisits_;
  if (pending_trained_) r.trained.push_back(*pending_trained_);
  pending_trained_.reset();
  r.n_trained = static_cast<int8_t>(r.trained.size());
  publish(ch::result, r);
  log_->info("run '{}' learned: weights checksum {}", runId(), r.weights_checksum);
  handled(config().steps);
  setState(process_status_t::DONE);
}

// Intrinsic phase (the one with snapshots). The forward models' updates still
// pending are made first: nothing in the intrinsic phase reads those models,
// and they get the same updates in the same order, so the run's results are
// those of a run without snapshots.
void PredictorsNode::prepareSnapshot() {
  trainPendingEffects();
  if (trainer_) trainer_->drain();  // the forward models as they stand after every effect so far
}

void PredictorsNode::saveState(SnapshotWriter& w) {
  w.i64(current_);
  w.i64(static_cast<std::int64_t>(outcome_));
  w.i64(action_);
  w.i64(look_);
  w.i64(revisits_);
  w.i64(finished_ ? 1 : 0);
  w.i64(static_cast<std::int64_t>(probes_.size()));
  for (const auto& p : probes_) w.blob(p);
  std::vector<std::uint8_t> focus(static_cast<std::size_t>(current_ >= 0 ? focus_.getEncodedSize() : 0));
  if (!focus.empty()) focus_.encode(focus.data(), 0, static_cast<int>(focus.size()));
  w.blob(focus);
  w.i64(pending_trained_ ? 1 : 0);
  if (pending_trained_) {
    const trained_t& t = *pending_trained_;
    w.i64(t.step);
    w.i64(t.action);
    w.i64(t.affordance ? 1 : 0);
    w.f64(t.affordance_before);
    w.f64(t.affordance_after);
    w.f64(t.learning_progress);
    w.i64(t.effect_trained ? 1 : 0);
  }
  requests_.save(w);
  core_->save(w);
}

void PredictorsNode::loadState(SnapshotReader& r) {
  current_ = r.within("current step", -1, config().steps);
  outcome_ = static_cast<Outcome>(r.within("outcome", static_cast<int>(Outcome::Unknown), static_cast<int>(Outcome::Learned)));
  action_ = static_cast<int>(r.within("action", -1, kNumActions - 1));
  look_ = static_cast<int>(r.within("look", -1, std::numeric_limits<int>::max()));
  revisits_ = r.within("revisits", 0, config().steps);
  finished_ = r.within("finished", 0, 1) == 1;
  const std::size_t image = 3u * static_cast<std::size_t>(config().eye.focus_side) * config().eye.focus_side;
  probes_.resize(static_cast<std::size_t>(r.within("probes", 0, config().protocol.limits.objects)));
  for (auto& p : probes_) p = r.blob("probe image", image);
  const std::vector<std::uint8_t> focus = r.blob("focus", static_cast<std::size_t>(config().protocol.bus.max_message_bytes));
  if (!focus.empty()) {
    std::string why;
    if (!decodeChecked(focus.data(), focus.size(), edge().context(), focus_, why)) r.refuse("focus", why);
  }
  pending_trained_.reset();
  if (r.within("pending update report", 0, 1) == 1) {
    trained_t t;
    t.run_id = runId();
    t.step = r.within("report step", 0, config().steps);
    t.action = static_cast<int8_t>(r.within("report action", 0, kNumActions - 1));
    t.affordance = r.within("report affordance", 0, 1) == 1;
    t.affordance_before = r.f64("report affordance before");
    t.affordance_after = r.f64("report affordance after");
    t.learning_progress = r.f64("report learning progress");
    t.effect_trained = r.within("report effect trained", 0, 1) == 1;
    pending_trained_ = t;
  }
  pending_effects_.clear();
  requests_.load(r);
  core_->load(r);
}

}  // namespace afford
