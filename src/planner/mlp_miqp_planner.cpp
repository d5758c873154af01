// The paper's Algorithm 1 (MLP-MIQP): classify the scene once; if a lane
// change is not worth trying, fall back. Otherwise the action network acts
// every step, and before each action its policy is rolled forward over the
// look-ahead against the predicted cars: a predicted collision or a broken
// limit hands the rest of the manoeuvre to the exact expert (the take-over),
// and the fallback acts where the expert finds no plan either.
#include "planner/mlp_miqp_planner.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <span>

#include "lanechange/checks.hpp"
#include "lanechange/ego.hpp"
#include "lanechange/error.hpp"
#include "lanechange/traffic.hpp"

namespace lanechange::planner {

namespace {

using Getter = std::function<double(const Observation&)>;

// Where each input column of the data set (docs/dataset.md) comes from in an
// observation: the initial scene, the time, the ego now, the cars now.
const std::map<std::string, Getter>& input_sources() {
  static const std::map<std::string, Getter> sources = [] {
    std::map<std::string, Getter> m;
    m["ego_x0"] = [](const Observation& o) { return o.scene->ego.x; };
    m["ego_y0"] = [](const Observation& o) { return o.scene->ego.y; };
    m["ego_v0"] = [](const Observation& o) { return o.scene->ego.v; };
    m["ego_theta0"] = [](const Observation& o) { return o.scene->ego.theta; };
    m["ego_a0"] = [](const Observation& o) { return o.scene->ego.a; };
    m["t"] = [](const Observation& o) { return o.t; };
    m["x"] = [](const Observation& o) { return o.ego.x; };
    m["y"] = [](const Observation& o) { return o.ego.y; };
    m["v"] = [](const Observation& o) { return o.ego.v; };
    m["theta"] = [](const Observation& o) { return o.ego.theta; };
    for (const Role car : kRoles) {
      const std::string name(to_string(car));
      m[name + "_x0"] = [car](const Observation& o) { return o.scene->car(car).x; };
      m[name + "_v0"] = [car](const Observation& o) { return o.scene->car(car).v; };
      m[name + "_a0"] = [car](const Observation& o) { return o.scene->car(car).a; };
      m[name + "_x"] = [car](const Observation& o) { return o.car(car).x; };
      m[name + "_v"] = [car](const Observation& o) { return o.car(car).v; };
      m[name + "_a"] = [car](const Observation& o) { return o.car(car).a; };
    }
    return m;
  }();
  return sources;
}

std::vector<std::string> names_of(const learn::Model& model, const char* which) {
  try {
    return model.description().at("features").at(which).get<std::vector<std::string>>();
  } catch (const nlohmann::json::exception& e) {
    throw InputError("model", std::string("model.json lists no features.") + which);
  }
}

}  // namespace

// The paper's choice: the SVM's class of the 13 features, and the gap
// between the follower and the target.
static MlpMiqpPlanner::SceneClassifier scene_classifier(std::shared_ptr<const learn::Model> model) {
  auto features = std::make_shared<const PolicyInputs>(names_of(*model, "classifier"));
  return [model = std::move(model), features](const Scenario& s) {
    Observation start;
    start.scene = &s;
    start.ego = s.ego;
    start.cars.reserve(s.car_count());
    for (const OtherCar& car : s.cars) start.cars.push_back(car.state);
    const Eigen::MatrixXd row = features->read(start).transpose();
    const int label =
        model->classify(learn::ClassifierKind::Svm, learn::FeatureSet::Plain, row).front();
    MlpMiqpPlanner::SceneChoice choice{label != static_cast<int>(Label::Failure), {}};
    if (s.has_every_role()) {
      choice.gap = {s.index_of(Role::Follower), s.index_of(Role::Target)};
    }
    return choice;
  };
}

// The gap classifier that most often named a gap the expert completes (or
// rightly none) on the held-out scenes.
static learn::ClassifierKind best_gap_classifier(const learn::Model& model) {
  learn::ClassifierKind best = learn::ClassifierKind::Svm;
  const auto scores = model.metrics().find("gap_classifiers");
  if (scores == model.metrics().end() || !scores->is_object()) return best;
  double best_share = -1.0;
  for (const learn::ClassifierKind kind : learn::kClassifierKinds) {
    const auto score = scores->find(std::string(learn::classifier_name(kind)));
    const double share =
        score != scores->end() && score->is_object() ? score->value("completable_share", 0.0) : 0.0;
    if (share > best_share) {
      best = kind;
      best_share = share;
    }
  }
  return best;
}

// Past the paper: the gap classifier names a slot around the ego (or none),
// and the network drives to that slot's gap.
static MlpMiqpPlanner::SceneClassifier gap_classifier(std::shared_ptr<const learn::Model> model) {
  if (!model->has(learn::FeatureSet::Gaps) ||
      names_of(*model, "classifier_gaps") != expert::gap_feature_names()) {
    throw InputError("model",
                     "the network drives to a chosen gap, and the model has no gap classifier "
                     "over this version's gap features");
  }
  const learn::ClassifierKind kind = best_gap_classifier(*model);
  return [model = std::move(model), kind](const Scenario& s) {
    const expert::GapSlots slots = expert::gap_slots(s);
    const std::vector<double> features = expert::gap_features(s, slots);
    const Eigen::MatrixXd row =
        Eigen::Map<const Eigen::RowVectorXd>(features.data(), std::ssize(features));
    const int slot = model->classify(kind, learn::FeatureSet::Gaps, row).front();
    MlpMiqpPlanner::SceneChoice choice;
    if (slot >= 0 && slot < expert::kGapSlots) {
      if (const auto& gap = slots.gaps[static_cast<std::size_t>(slot)]) {
        choice = {true, expert::frame_of(*gap)};
      }
    }
    return choice;
  };
}

static MlpMiqpPlanner::Network network_of(std::shared_ptr<const learn::Model> model,
                                          std::shared_ptr<const PolicyInputs> inputs) {
  return [model = std::move(model), inputs = std::move(inputs)](const Observation& o,
                                                                const expert::GapFrame& gap) {
    const Eigen::Vector2d u = model->policy().act(inputs->read(o, gap));
    return EgoControl{u[0], u[1]};
  };
}

// A name both lists know ("leader_a") is the gap view's for a network that
// reads the gap: its data took it from the view, which also reads a scene
// without a leader role.
PolicyInputs::PolicyInputs(const std::vector<std::string>& names) {
  const auto& view = expert::gap_view_names();
  const auto in_view = [&view](const std::string& name) {
    return std::find(view.begin(), view.end(), name) != view.end();
  };
  reads_gap_ = std::any_of(names.begin(), names.end(), [&](const std::string& name) {
    return in_view(name) && !input_sources().contains(name);
  });
  for (const std::string& name : names) {
    const auto source = input_sources().find(name);
    if (source != input_sources().end() && !(reads_gap_ && in_view(name))) {
      sources_.push_back({&source->second, 0});
      continue;
    }
    const auto at = std::find(view.begin(), view.end(), name);
    if (at == view.end()) {
      throw InputError("model", "the network wants the input \"" + name +
                                    "\", which an observation does not give");
    }
    sources_.push_back({nullptr, static_cast<std::size_t>(at - view.begin())});
  }
}

learn::Observation PolicyInputs::read(const Observation& o, const expert::GapFrame& gap) const {
  std::array<double, expert::kGapViewSize> view{};
  if (reads_gap_) view = expert::gap_view(*o.scene, o.cars, o.ego, gap);
  learn::Observation x(static_cast<Eigen::Index>(sources_.size()));
  for (std::size_t i = 0; i < sources_.size(); ++i) {
    const Source& source = sources_[i];
    x[static_cast<Eigen::Index>(i)] =
        source.getter != nullptr ? (*source.getter)(o) : view[source.view];
  }
  return x;
}

MlpMiqpPlanner::MlpMiqpPlanner(Config config, SceneClassifier classify, Network network,
                               std::shared_ptr<const expert::LaneChangeSolver> solver,
                               std::string name, bool reads_roles)
    : config_(closed_loop_expert(std::move(config))),
      classify_(std::move(classify)),
      network_(std::move(network)),
      expert_(config_, std::move(solver)),
      name_(std::move(name)),
      reads_roles_(reads_roles) {}

static std::shared_ptr<const PolicyInputs> action_inputs_of(const learn::Model& model) {
  return std::make_shared<const PolicyInputs>(names_of(model, "action_inputs"));
}

MlpMiqpPlanner::MlpMiqpPlanner(Config config, const std::shared_ptr<const learn::Model>& model,
                               std::shared_ptr<const expert::LaneChangeSolver> solver)
    : MlpMiqpPlanner(std::move(config), {}, {}, std::move(solver)) {
  auto inputs = action_inputs_of(*model);
  reads_roles_ = !inputs->reads_gap();
  classify_ = reads_roles_ ? scene_classifier(model) : gap_classifier(model);
  network_ = network_of(model, std::move(inputs));
}

std::shared_ptr<const MlpMiqpPlanner> make_oracle_mlp_miqp(
    const Config& config, const std::shared_ptr<const learn::Model>& model) {
  auto solver = std::make_shared<expert::FastLaneChangeSolver>();
  auto oracle = std::make_shared<const expert::ExpertPlanner>(closed_loop_expert(config), solver);
  auto keeper = std::make_shared<const LaneKeeper>(oracle->config());
  MlpMiqpPlanner::Network network = [oracle, keeper](const Observation& o,
                                                     const expert::GapFrame& /*gap*/) {
    const expert::ExpertResult plan = oracle->plan(scene_now(o, oracle->config()));
    if (plan.status != expert::PlanStatus::Converged || plan.path.controls.empty()) {
      return fallback_control(*keeper, o);
    }
    const auto& u = plan.path.controls.front();
    return EgoControl{u(0), u(1)};
  };
  // The model's own way of choosing: the paper's, or the gap classifier's.
  const bool reads_roles = !action_inputs_of(*model)->reads_gap();
  return std::make_shared<MlpMiqpPlanner>(
      config, reads_roles ? scene_classifier(model) : gap_classifier(model), std::move(network),
      std::move(solver), "mlp-miqp-oracle", reads_roles);
}

bool MlpMiqpPlanner::tries(const Scenario& scene) const { return classify_(scene).tries; }

// A network that reads the paper's three cars cannot read a scene without
// one of them: there the expert drives from the start.
std::unique_ptr<PlannerSession> MlpMiqpPlanner::start(const Scenario& scene) const {
  if (reads_roles_ && !scene.has_every_role()) {
    return std::make_unique<MlpMiqpSession>(*this, SceneChoice{true, {}}, true);
  }
  return std::make_unique<MlpMiqpSession>(*this, choose(scene), false);
}

MlpMiqpSession::MlpMiqpSession(const MlpMiqpPlanner& planner, MlpMiqpPlanner::SceneChoice choice,
                               bool expert_only)
    : planner_(planner),
      gap_(choice.gap),
      keeper_(planner.config()),
      expert_(planner.expert(), planner.config()),
      refused_(!choice.tries),
      expert_in_charge_(expert_only),
      expert_only_(expert_only) {}

Decision MlpMiqpSession::act(const Observation& o) {
  if (refused_) return refused(o);
  if (expert_in_charge_) return expert_decision(o, "");
  return network_decision(o);
}

Decision MlpMiqpSession::network_decision(const Observation& o) {
  y_peak_ = std::max(y_peak_, o.ego.y);
  const EgoControl u = network_control(o);
  const std::string problem = check_ahead(o, u);
  if (problem.empty()) return {u, ActStatus::Planned, ""};
  expert_in_charge_ = true;
  return expert_decision(o, problem);
}

Decision MlpMiqpSession::expert_decision(const Observation& o, const std::string& why) {
  Decision d = expert_.act(o);
  // The step of the take-over is one whatever the expert finds; after it,
  // the expert's own status tells whether it planned or fell back.
  if (!why.empty()) {
    d.reason = "take-over: " + why + (d.reason.empty() ? "" : "; " + d.reason);
    d.status = ActStatus::TookOver;
  } else if (d.status == ActStatus::Planned) {
    d.status = ActStatus::TookOver;
    d.reason = expert_only_ ? "the expert drives: the network reads a leader, a follower and a "
                              "target, and the scene lacks one"
                            : "the expert drives since the take-over";
  }
  return d;
}

// A refusal of the classifier is a prediction, wrong in about one scene of
// seven (Table I); the expert checks it now and then, so a scene the expert
// masters is not lost to the fallback for good.
Decision MlpMiqpSession::refused(const Observation& o) {
  const int period = planner_.config().closed_loop.refusal_check_period;
  const std::string refusal = "the classifier expects no lane change to succeed";
  if (period == 0 || o.step < next_check_) {
    return {fallback_control(keeper_, o), ActStatus::Fallback, refusal};
  }
  Decision d = expert_.act(o);
  if (d.status != ActStatus::Planned) {
    // A check cut short by its budget decided nothing: the next step's
    // scene, a step shorter, is checked at once.
    const bool undecided = expert_.last_status() == expert::PlanStatus::TimeLimit ||
                           expert_.last_status() == expert::PlanStatus::WorkLimit;
    next_check_ = o.step + (undecided ? 1 : period);
    d.reason = refusal + "; the expert's check agrees (" + d.reason + ")";
    return d;
  }
  refused_ = false;
  // A network that drives to any gap is handed the gap the expert found;
  // the paper's network knows one gap only, so the expert drives on.
  if (!planner_.reads_roles()) {
    gap_ = expert_.plan_gap();
    return network_decision(o);
  }
  expert_in_charge_ = true;
  d.status = ActStatus::TookOver;
  d.reason = "take-over: " + refusal + ", but the expert's check found a plan";
  return d;
}

// Below the target lane's centre the ego's heading never turns back past
// parallel to the road, so y never moves back towards the ego lane: the
// closed-loop expert's rule (closed_loop.monotone_lateral), kept by the
// network's controls. The network's small lateral wobbles would otherwise
// read as reversals and hand many lane changes to the expert.
static EgoControl keep_lateral_monotone(EgoControl u, const Observation& o) {
  const double dt = o.scene->horizon / o.scene->steps;
  if (o.ego.y < o.scene->lane_width) u.omega = std::max(u.omega, -o.ego.theta / dt);
  return u;
}

EgoControl MlpMiqpSession::network_control(const Observation& o) const {
  const EgoControl u = planner_.network(o, gap_);
  const bool monotone = !planner_.reads_roles() && planner_.config().closed_loop.monotone_lateral;
  return monotone ? keep_lateral_monotone(u, o) : u;
}

namespace {

std::string network_hit(const Scenario& scene, CarIndex car, double in_seconds) {
  return "the network would hit the " + scene.cars[car].id + " in " + std::to_string(in_seconds) +
         " s";
}

// m: how far short of Eq. 1's safe distance a gap network's look-ahead may
// enter the target lane. The expert's own plans, followed step by step
// (mlp-miqp-oracle), come up to 0.28 m short in the look-ahead on sampled
// dense scenes: the check must pass what the expert itself does.
constexpr double kGapNetworkSafeDistanceSlack = 0.5;

// The shortfall is in the reason: the expert's own plans touch these
// distances, so how far the network misses them says how near it came.
std::string short_of_safe_distance(const Scenario& scene, CarIndex car, double shortfall) {
  char what[160];
  std::snprintf(what, sizeof what,
                "the network would enter the target lane %.2f m short of the %s's safe distance",
                shortfall, scene.cars[car].id.c_str());
  return what;
}

// The expert's own rule (Eq. 1): once the ego's body touches the target
// lane it keeps the safe distance ahead of the gap's car behind and behind
// its car ahead. A network that breaks it is about to cut in where the
// expert never would; taking over then, before the cut-in, leaves the
// expert a feasible plan that later would not exist.
std::string too_close_in_target_lane(const Observation& o, const Scenario& scene,
                                     const expert::GapFrame& gap, double slack) {
  const double w = scene.lane_width;
  if (o.ego.y + scene.vehicle.width / 2.0 <= w / 2.0) return "";
  const SafetyMargins d = scene.centre_safe_distances();
  // Behind the gap's car behind (when it is ahead) is not where the expert
  // changes lanes; nor ahead of its car ahead (when it is behind).
  if (gap.behind) {
    const CarState& behind = o.car(*gap.behind);
    const double short_by =
        behind.x + d.follower.standstill + d.follower.time_headway * behind.v - o.ego.x;
    if (short_by > slack) return short_of_safe_distance(scene, *gap.behind, short_by);
  }
  if (gap.ahead) {
    const CarState& ahead = o.car(*gap.ahead);
    const double short_by =
        o.ego.x + d.target.time_headway * o.ego.v - (ahead.x - d.target.standstill);
    if (short_by > slack) return short_of_safe_distance(scene, *gap.ahead, short_by);
  }
  return "";
}

// The expert's own bound on the braking its cut-in forces on a car that
// reacts to the ego (expert.cut_in_decel; none in the paper's formulation),
// checked on the cars as the look-ahead predicts them.
std::string forced_braking(const Observation& o, const TrafficModel& traffic,
                           const Config& config) {
  if (!config.expert.cut_in_decel) return "";
  for (CarIndex c = 0; c < o.cars.size(); ++c) {
    if (traffic.followed_ego(c) && -o.cars[c].a > *config.expert.cut_in_decel) {
      char what[160];
      std::snprintf(what, sizeof what, "the network would make the %s brake at %.2f m/s^2",
                    o.scene->cars[c].id.c_str(), -o.cars[c].a);
      return what;
    }
  }
  return "";
}

bool at_node(double t, double when, double dt) { return t >= when - 1e-9 && t < when + dt - 1e-9; }

// The expert's plans cross the lane line before t_f and settle on the target
// lane's centre by the end of the run (t_f plus closed_loop.settle_time), as
// the judge asks. A network whose look-ahead misses either has stalled below
// or across the line (out of its training distribution, e.g. faster
// traffic) and would end the run a failure, while the expert still has the
// time to finish the change.
std::string late(const Observation& o, const Scenario& scene, const Config& config) {
  const double dt = scene.horizon / scene.steps;
  const double w = scene.lane_width;
  char what[120];
  if (at_node(o.t, scene.horizon, dt) && o.ego.y < w / 2.0) {
    std::snprintf(what, sizeof what,
                  "the network would not have crossed the lane line at t_f (y %.2f m)", o.ego.y);
    return what;
  }
  const double miss = std::abs(o.ego.y - w);
  if (at_node(o.t, scene.horizon + config.closed_loop.settle_time, dt) &&
      miss > config.labels.reach) {
    std::snprintf(what, sizeof what,
                  "the network would end the run %.2f m off the target lane's centre", miss);
    return what;
  }
  return "";
}

}  // namespace

// The policy rolled forward against the cars as their behavior predicts
// them from now (IDM reacting to the rolled-out ego), through the planner's
// model of the ego, its controls saturated at the limits. Empty when the
// look-ahead stays on the road, within the speed bounds, out of the target
// lane's safe distances, without a reversal and clear of the cars.
std::string MlpMiqpSession::check_ahead(const Observation& now, EgoControl first) {
  if (window_fits(now)) return extend_window();
  return roll_out(now, first);
}

std::string MlpMiqpSession::roll_out(const Observation& now, EgoControl first) {
  const Config& config = planner_.config();
  const double dt = now.scene->horizon / now.scene->steps;
  const int steps = static_cast<int>(std::lround(config.closed_loop.lookahead / dt));
  Window& w = window_;
  w.step = now.step;
  w.scene = scene_now(now, config);
  w.traffic.emplace(*w.scene, config);
  w.ego.assign(1, now.ego);
  w.ahead.clear();
  w.cars.dt = dt;
  w.cars.cars.resize(w.traffic->car_count());
  for (CarIndex c = 0; c < w.traffic->car_count(); ++c) {
    CarTrack& track = w.cars.cars[c];
    const CarState& car = w.traffic->car(c);
    track.x.assign(1, car.x);
    track.v.assign(1, car.v);
    track.a.assign(1, car.a);
  }
  w.last = now;
  w.next = first;
  for (int k = 1; k <= steps; ++k) {
    advance_window(dt);
    if (std::string problem = check_node(k); !problem.empty()) {
      w.step = -1;
      return problem;
    }
  }
  if (const auto hit = first_collision(w.ego, w.cars, *w.scene)) {
    w.step = -1;
    return network_hit(*w.scene, hit->car, hit->time);
  }
  return "";
}

// The window predicted at the last step still describes this one: node 1
// is where the ego and the cars are now, within the tolerance (for the
// heading, the error that moves the ego by the tolerance over the look-ahead).
bool MlpMiqpSession::window_fits(const Observation& now) const {
  const double tolerance = planner_.config().closed_loop.lookahead_tolerance;
  if (tolerance <= 0.0 || window_.step != now.step - 1 || window_.ego.size() < 2) return false;
  const EgoState& ego = window_.ego[1];
  const double heading_tolerance =
      tolerance / std::max(1.0, now.ego.v * planner_.config().closed_loop.lookahead);
  if (std::abs(ego.x - now.ego.x) > tolerance || std::abs(ego.y - now.ego.y) > tolerance ||
      std::abs(ego.v - now.ego.v) > tolerance ||
      std::abs(ego.theta - now.ego.theta) > heading_tolerance) {
    return false;
  }
  for (CarIndex c = 0; c < now.cars.size(); ++c) {
    const CarTrack& track = window_.cars.car(c);
    if (std::abs(track.x[1] - now.car(c).x) > tolerance ||
        std::abs(track.v[1] - now.car(c).v) > tolerance) {
      return false;
    }
  }
  return true;
}

// Drops node 0 and adds a node at the end: the nodes between passed their
// checks at earlier steps, so only the new node and the new segment are checked.
std::string MlpMiqpSession::extend_window() {
  Window& w = window_;
  const double dt = w.cars.dt;
  w.ego.erase(w.ego.begin());
  // Node 1's observation keeps its buffer for the new node (no allocation).
  recycled_ = std::move(w.ahead.front());
  w.ahead.erase(w.ahead.begin());
  for (CarTrack& track : w.cars.cars) {
    track.x.erase(track.x.begin());
    track.v.erase(track.v.begin());
    track.a.erase(track.a.begin());
  }
  ++w.step;
  advance_window(dt);
  const int ahead = static_cast<int>(w.ego.size()) - 1;
  if (std::string problem = check_node(ahead); !problem.empty()) {
    w.step = -1;
    return problem;
  }
  segment_.dt = dt;
  segment_.cars.resize(w.cars.cars.size());
  for (std::size_t c = 0; c < segment_.cars.size(); ++c) {
    const CarTrack& from = w.cars.cars[c];
    CarTrack& to = segment_.cars[c];
    to.x.assign(from.x.end() - 2, from.x.end());
    to.v.assign(from.v.end() - 2, from.v.end());
    to.a.assign(from.a.end() - 2, from.a.end());
  }
  const std::span<const EgoState> last_step(w.ego.end() - 2, 2);
  if (const auto hit = first_collision(last_step, segment_, *w.scene)) {
    w.step = -1;
    return network_hit(*w.scene, hit->car, hit->time + (ahead - 1) * dt);
  }
  return "";
}

void MlpMiqpSession::advance_window(double dt) {
  Window& w = window_;
  Observation& o = w.last;
  EgoControl u = w.next;
  // The actuators saturate (the simulator clips the same way): a network
  // that asks for a little more than the limit is not a danger by itself.
  (void)clip_to_limits(u, o.ego, o.scene->limits, dt);
  w.traffic->step(dt, {o.ego.x, o.ego.y, o.ego.v});
  o.ego = step_trapezoidal(o.ego, u, dt);
  o.ego.a = u.a;
  o.t += dt;
  ++o.step;
  w.ego.push_back(o.ego);
  for (CarIndex c = 0; c < w.traffic->car_count(); ++c) {
    const CarState& car = w.traffic->car(c);
    o.cars[c] = car;
    CarTrack& track = w.cars.cars[c];
    // The acceleration applied from the last node on is known only now.
    track.a.back() = car.a;
    track.x.push_back(car.x);
    track.v.push_back(car.v);
    track.a.push_back(car.a);
  }
  recycled_ = o;
  w.ahead.push_back(std::move(recycled_));
  w.next = network_control(o);
}

// The tests of one node of the window (its last, `ahead` steps from now).
std::string MlpMiqpSession::check_node(int ahead) {
  const Scenario& scene = *window_.last.scene;
  const Observation& o = window_.last;
  if (!scene.limits.v.contains(o.ego.v) || !body_on_road(o.ego.y, scene)) {
    char what[160];
    std::snprintf(what, sizeof what,
                  "the network leaves the speed or road bounds %d steps ahead (v %.2f m/s, "
                  "y %.2f m)",
                  ahead, o.ego.v, o.ego.y);
    return what;
  }
  const double slack = planner_.reads_roles() ? 0.0 : kGapNetworkSafeDistanceSlack;
  if (const std::string close = too_close_in_target_lane(o, scene, gap_, slack); !close.empty()) {
    return close + " " + std::to_string(ahead) + " steps ahead";
  }
  if (!planner_.reads_roles()) {
    const std::string braking = forced_braking(o, *window_.traffic, planner_.config());
    if (!braking.empty()) return braking + " " + std::to_string(ahead) + " steps ahead";
  }
  // The judge calls a move back towards the ego lane beyond its tolerance
  // ill-posed; the take-over comes at half of it, while it can be stopped.
  const LabelTolerances& tolerances = planner_.config().labels;
  const double cap =
      tolerances.reference == ReversalReference::TargetCenter ? scene.lane_width : INFINITY;
  lateral_.assign(1, std::min(y_peak_, cap));
  for (const EgoState& e : window_.ego) lateral_.push_back(e.y);
  if (const double back = largest_lateral_reversal(lateral_, cap);
      back > tolerances.reversal / 2.0) {
    char what[120];
    std::snprintf(what, sizeof what,
                  "the network would move %.2f m back towards the ego lane %d steps ahead", back,
                  ahead);
    return what;
  }
  return late(o, scene, planner_.config());
}

}  // namespace lanechange::planner
