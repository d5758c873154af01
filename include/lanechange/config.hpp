#pragma once
// Every tunable number of the project lives here, with the defaults of
// docs/config.md (which cites NOTES.md and the paper). A Config can be saved
// to and loaded from JSON; a loaded file may give any subset of the fields.
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace lanechange {

struct VehicleSize {
  double length = 4.4;  ///< m, bumper to bumper (the authors' car length)
  double width = 1.7;   ///< m (the authors' body half-width is 0.85 m)
};

struct Interval {
  double lo = 0.0;
  double hi = 0.0;
  [[nodiscard]] bool contains(double value) const { return lo <= value && value <= hi; }
};

/// The ego's limits. Defaults from the authors' code (NOTES.md).
struct Limits {
  Interval v{0.0, 60.0 / 3.6};                                ///< m/s
  Interval a{-6.0, 6.0};                                      ///< m/s^2
  Interval omega{-0.26179938779914941, 0.26179938779914941};  ///< rad/s, 15 deg/s
  double lateral_margin = 3.75 / 15.0;  ///< m; y stays in [-margin, w + margin]
};

/// Intelligent Driver Model (Treiber, Hennecke, Helbing 2000).
struct IdmParameters {
  double desired_speed = 40.0 / 3.6;  ///< v0, m/s
  double time_headway = 1.5;          ///< T, s
  double min_gap = 2.0;               ///< s0, m (bumper to bumper)
  double max_accel = 1.0;             ///< a, m/s^2
  double comfortable_decel = 1.67;    ///< b, m/s^2
  double exponent = 4.0;              ///< delta
};

/// One safe distance of Eq. 1: Delta = standstill + time_headway * v, where v
/// is the ego's speed for a car ahead of it and the follower's speed for the
/// follower. Measured centre to centre, so a standstill below the car length
/// allows contact.
struct SafeDistance {
  double standstill = 0.0;    ///< m
  double time_headway = 0.0;  ///< s
};

struct SafetyMargins {
  SafeDistance leader{8.4, 0.5};  ///< car length + 4 m, plus half a second
  SafeDistance follower{8.4, 0.5};
  SafeDistance target{8.4, 0.5};
};

enum class LaneRule {
  /// The paper's Eq. 1 read literally: the ego's centre decides its one lane,
  /// so optimal plans may drive astride the line (docs/expert.md).
  EitherOr,
  /// The ego is in every lane its body touches (the authors' code): the default.
  /// The body is taken unturned, so only its centre is bounded: at a heading
  /// the front corner reaches past the line (docs/expert.md, "The heading").
  Footprint,
  /// As Footprint, with the body turned by its heading: the corners, to first
  /// order in the heading, decide which lanes the body touches.
  FootprintHeading,
};

enum class JerkWeighting {
  Derivative,  ///< c2 * (da/dt)^2 integrated, as the paper's text
  Difference,  ///< c2 * (a_{k+1} - a_k)^2 summed times dt, as the authors' code
};

enum class WarmStart {
  Quintic,  ///< the paper's quintic in x and y, aimed behind the target (NOTES.md)
  Authors,  ///< the authors' code: x = v0 t, quintic y, v linear to the target's speed
};

/// How the traffic models integrate a step. The authors' prediction uses Euler.
enum class TrafficIntegration {
  Ballistic,  ///< x += v dt + a dt^2 / 2 (Treiber and Kesting's scheme)
  Euler,      ///< v += a dt, then x += v dt (semi-implicit; the authors' prediction)
};

/// When a car takes the ego for the car ahead of it in its lane.
enum class SeesEgo {
  InLane,       ///< once the ego's body is in its lane: a driver who watches the line
  Overlapping,  ///< once the ego's body overlaps its own width: SUMO's sublane model
};

/// What the expert does where its plain rounds fail (docs/expert.md, "Rounds that never
/// converge").
enum class Globalisation {
  Off,          ///< a cycle or the round limit ends the plan (a failure), as before
  TrustRegion,  ///< then more rounds, each within a shrinking box of the last (trust_*)
};

/// Which gaps of the target lane the expert may merge into (docs/expert.md, "The gap").
enum class GapChoice {
  Fixed,  ///< only between the follower and the target: the paper's Eq. 1
  Best,   ///< every gap, ahead of and behind each target-lane car; the best plan wins
};

struct ExpertSettings {
  double horizon = 5.0;            ///< t_f, s
  int steps = 50;                  ///< N
  double weight_accel = 0.5;       ///< c1
  double weight_jerk = 100.0;      ///< c2
  double weight_lateral = 1.0;     ///< c3
  double weight_terminal_x = 0.0;  ///< pull of x_N towards the aim point (authors: 0.005)
  /// A tiny price on omega^2 (times dt). The paper puts none, so where the
  /// yaw rate does not matter the optimum is not unique (it chatters between
  /// bounds) and the QP is singular in it; this picks the calmest optimum
  /// and changes objectives by about 1e-6.
  double weight_yaw_rate = 1e-6;
  JerkWeighting jerk_weighting = JerkWeighting::Derivative;
  LaneRule lane_rule = LaneRule::Footprint;
  /// m: under the footprint rule the ego counts as in both lanes, with every
  /// target-lane distance, once its body comes this close to the line. A
  /// plan that waits for a gap otherwise rides the line with its body at
  /// it, where the cars behind in the target lane (SUMO's, a driver's)
  /// already take it as cutting in (docs/expert.md). 0: the body's edge.
  double line_clearance = 0.1;
  int max_iterations = 10;             ///< linearization rounds
  double convergence_tolerance = 0.1;  ///< m, largest change of x and y between rounds
  /// m: a round whose solution is this close to the one two rounds back,
  /// while consecutive rounds still differ by more than the convergence
  /// tolerance, has locked into a 2-cycle that no later round leaves; the plan
  /// stops there (status cycling, a failure like the round limit). 0: off.
  double cycle_tolerance = 1e-3;
  /// Entered only where the plain rounds end in a cycle or at the round limit,
  /// so every plan that converges without it keeps its rounds and its answer.
  Globalisation globalisation = Globalisation::TrustRegion;
  /// m: the first box, on x and y at every node, around the linearization point.
  double trust_radius = 0.5;
  /// The box shrinks by this factor when a round's step reverses the last one.
  double trust_shrink = 0.5;
  int trust_rounds = 10;                ///< rounds allowed after the plain ones
  double big_m = 1000.0;                ///< m; must exceed any distance a lane constraint relaxes
  bool fix_terminal_lateral = true;     ///< y(t_f) = w as a constraint (authors' code)
  bool constrain_initial_node = false;  ///< apply the lane rules at t = 0 too (authors' code)
  /// Node k is checked against the other cars' prediction at node k + this
  /// (the authors' code has an off-by-one of 1).
  int prediction_lead_steps = 0;
  /// Keep the heading at or above 0 (from the first node the yaw rate can
  /// reach it), so y never decreases: the plan cannot swing back towards the
  /// ego lane to take a run-up at the line (docs/closed_loop.md). Not in the
  /// paper, whose labels call such plans ill-posed instead.
  bool monotone_lateral = false;
  /// m; above 0, the yaw rate is bounded by the speed, |omega| <= v / R, as a
  /// car's steering bounds its curvature: no turning on the spot. 0 leaves the
  /// unicycle's bound of limits.omega alone, as the paper does.
  double min_turn_radius = 0.0;
  WarmStart warm_start = WarmStart::Quintic;
  /// Where the warm start and the terminal-x term aim: behind the target by
  /// its safe distance (NOTES.md), or at the target itself (authors' code).
  bool aim_behind_target = true;
  GapChoice gap = GapChoice::Best;
  /// m/s^2: the hardest braking a plan may force on the car it cuts in ahead
  /// of, as the traffic model has that car react (MOBIL's b_safe): the ego
  /// keeps, behind it, the larger of Eq. 1's distance and the gap at which
  /// the car brakes no harder. Below closed_loop.unsafe_decel, for the
  /// linearization's slack. None (JSON null): Eq. 1 alone, the paper.
  std::optional<double> cut_in_decel = 3.5;
  /// s: an ego that starts closer behind a car than Eq. 1 allows (recorded
  /// traffic, or a car that cut in) restores the distance within this time,
  /// its shortfall at the start shrinking linearly to nothing; 0 asks for the
  /// whole distance from node 1 on (the paper), which such a start cannot meet.
  double restore_distance_within = 3.0;
};

/// What a drop of y is measured from, for "y never decreases".
enum class ReversalReference {
  /// The running maximum of y, capped at the target-lane centre: the ego may
  /// overshoot the centre and settle back (lane keeping), but must not move
  /// back towards its old lane, before or after reaching the centre.
  TargetCenter,
  /// The running maximum of y itself: the paper's words taken literally, so
  /// any settling after an overshoot counts.
  RunningMax,
};

/// The labeller of NOTES.md (Sec. III of the paper).
struct LabelTolerances {
  double reach = 0.25;     ///< m: |y(t_f) - w| within this counts as reaching the TL
  double reversal = 0.10;  ///< m: a larger drop of y (see reference) is a reversal
  ReversalReference reference = ReversalReference::TargetCenter;
  double max_final_heading = 0.17453292519943295;  ///< rad, 10 deg
};

/// The random scenario sampler (docs/scenarios.md).
struct SamplerSettings {
  Interval leader_speed{20.0 / 3.6, 40.0 / 3.6};    ///< vehicle 1, m/s
  Interval follower_speed{20.0 / 3.6, 40.0 / 3.6};  ///< vehicle 2, m/s
  Interval target_speed{20.0 / 3.6, 40.0 / 3.6};    ///< vehicle 3, m/s
  Interval ego_speed_ratio{0.9, 1.1};               ///< ego speed / leader speed
  Interval leader_headway{3.0, 5.0};      ///< s: the ego's time gap to the leader (>= 3 s rule)
  Interval follower_offset{-40.0, 10.0};  ///< m: follower centre relative to the ego
  Interval gap_length{1.0, 50.0};         ///< m: free space between follower and target bumpers
  Interval accel{-1.0, 1.0};              ///< m/s^2, for constant_accel
  /// How many cars the target lane holds, drawn uniformly from this range of
  /// whole numbers; [0, 0] draws the paper's scene (a follower and a target).
  /// Dense traffic also puts a car behind the ego in its lane (docs/scenarios.md).
  Interval target_lane_cars{0.0, 0.0};
  Interval rear_headway{1.0, 3.0};  ///< s: the car behind the ego's time gap, dense traffic
};

/// How the expert re-plans in closed loop (docs/closed_loop.md).
enum class HorizonMode {
  Receding,   ///< every re-plan looks expert.horizon ahead
  Shrinking,  ///< the re-plans end at the first plan's t_f (down to min_horizon)
};

/// What bounds a planner's step in closed loop (docs/closed_loop.md).
enum class Deadline {
  /// Budgets of work (closed_loop.step_qp_iterations, mpc.step_iterations),
  /// sized to fit step_budget_ms on the reference machine: the same command
  /// gives the same outcomes on any load. A step over step_budget_ms of wall
  /// time is counted as an overrun, and its decision stands.
  Work,
  /// As in a car: the planners also stop at the wall clock, and a step over
  /// step_budget_ms is overruled by the fallback.
  WallClock,
};

/// The closed loop: the simulator, the fallback and lane keeper, the
/// receding-horizon expert and the hierarchical planner (docs/closed_loop.md).
struct ClosedLoopSettings {
  double settle_time = 3.0;       ///< s the run goes on after the planning horizon
  double step_budget_ms = 100.0;  ///< the step's deadline (see deadline)
  Deadline deadline = Deadline::Work;
  /// The expert's interior-point iterations per step under Deadline::Work:
  /// the slowest step about 30 ms on the reference machine (docs/closed_loop.md).
  int step_qp_iterations = 1000;
  int replan_period = 1;  ///< the expert re-plans every this many steps
  /// Shrinking: a receding plan keeps putting the crossing off to its end
  /// and waits at the line (docs/closed_loop.md).
  HorizonMode horizon_mode = HorizonMode::Shrinking;
  /// The closed-loop expert plans with expert.monotone_lateral on: without
  /// it, its plans swing back before the line to take a run-up.
  bool monotone_lateral = true;
  double min_horizon = 2.5;  ///< s: the shrinking horizon stops shrinking here
  /// Steps a failed re-plan may follow the last plan open loop before the
  /// fallback takes over: a stale plan drifts from the real state.
  int stale_plan_steps = 5;
  double settled_heading = 0.035;     ///< rad (2 deg): the manoeuvre is over when |theta| is below
  double settled_offset = 0.25;       ///< m from the target-lane centre, with the heading above
  double keeper_lateral_gain = 0.08;  ///< rad per m of offset from the lane centre (lane keeper)
  double keeper_heading_gain = 1.2;   ///< 1/s: yaw rate per rad of heading error
  /// s: the lane keeper also keeps up with a faster car behind it in its lane
  /// that would come within IDM's gap (s0 + v T) within this time (the other
  /// cars ignore the ego), as far as the car ahead and the ego's limits allow
  /// (docs/closed_loop.md); 0: the car ahead alone.
  double keeper_rear_horizon = 5.0;
  /// rad: the largest heading of the fallback's return to the ego lane while
  /// its body is still in the target lane (a cut-in backed out of). The
  /// default is the lane keeper's own; 0.3 backs out about twice as fast but
  /// was measured to leave the collisions where they were (docs/closed_loop.md,
  /// "Backing out").
  double keeper_backout_heading = 0.15;
  /// s the hierarchical planner checks its policy ahead. 3 s, not the issue's
  /// 1 s: with 1 s the take-over came when the expert could no longer finish;
  /// 3 s against 2 s took its own at-fault collisions from 18 to 7 in 15,000
  /// scenes (docs/closed_loop.md, "Results").
  double lookahead = 3.0;
  /// m and m/s: while the ego and the cars stay this close to where the last
  /// look-ahead put them, the next one extends it by a step instead of
  /// rolling the policy out again (docs/closed_loop.md); 0: roll out every step.
  double lookahead_tolerance = 0.02;
  /// Steps between the expert's checks of a scene the hierarchical planner's
  /// classifier refused, from the first step on; the first plan it finds
  /// takes over. 1, as `miqp` re-plans: a gap may open between two sparser
  /// checks; the price is an expert plan (2.7 ms median) per refused step. 0 is the paper's
  /// Algorithm 1: a refused scene is left to the fallback for good (docs/closed_loop.md).
  int refusal_check_period = 1;
  /// m/s^2: a rollout that made another car brake harder than this is an
  /// unsafe cut-in (MOBIL's b_safe), counted beside the at-fault collisions.
  double unsafe_decel = 4.0;
};

/// The wall-clock limit of a planner's step whose own limit is `own_ms`:
/// that under Deadline::WallClock; under Deadline::Work a guard against a
/// planner that hangs, ten step budgets, far beyond what the work budgets
/// take on the reference machine.
[[nodiscard]] double step_wall_limit_ms(const ClosedLoopSettings& c, double own_ms);

/// The paper's MPC baseline (docs/baselines.md, "mpc"). Its horizon, dt,
/// weights and limits are the expert's; these are its own.
struct MpcSettings {
  int circles = 3;      ///< circles along each car's length (the ego's too)
  double margin = 0.3;  ///< m kept between any ego circle and any other car's circle
  /// ms of wall time per solve (Ipopt 3.11 has only a CPU limit; the
  /// program's callback enforces the wall time)
  double time_limit_ms = 80.0;
  int max_iterations = 100;  ///< Ipopt iterations per solve
  /// Ipopt iterations per closed-loop step under closed_loop.deadline =
  /// work: about 80 ms on the reference machine (docs/baselines.md).
  int step_iterations = 12;
  double tolerance = 1e-4;  ///< Ipopt's tol
  /// End the horizon in the gap: y_N = w (the expert's fixed terminal
  /// lateral) and x_N between the follower's and target's safe distances.
  bool terminal_gap = true;
  /// m: a car's circles at a node enter the program only where the starting
  /// point passes within this of touching them (the solution is checked
  /// against the rest, and solved again around itself where it reaches them).
  double gate_distance = 3.0;
};

/// The dynamic window approach (docs/baselines.md, "dwa"; docs/baselines_sampling.md).
struct DwaSettings {
  double horizon = 1.5;        ///< s each constant control is rolled out
  int accel_samples = 7;       ///< samples of a across the window
  int yaw_rate_samples = 11;   ///< samples of omega across the window
  double max_jerk = 10.0;      ///< m/s^3: the window's half-width in a is this times dt
  double max_yaw_accel = 2.0;  ///< rad/s^2: the window's half-width in omega is this times dt
  double margin = 0.3;         ///< m the ego's box keeps from every predicted car
  double braking_decel = 4.0;  ///< m/s^2 both cars brake at in the "can stop safely" check
  /// Also keep Eq. 1's safe distances (scene.safe_distance) to the target
  /// lane's cars wherever the body is in that lane, as the expert does.
  bool keep_safe_distances = true;
  double desired_speed = 50.0 / 3.6;  ///< m/s the speed term pulls towards
  double goal_preview = 1.5;      ///< s: the heading goal sits this far ahead on the lane centre
  double weight_lateral = 3.0;    ///< per m of |y - goal lane centre| at the rollout's end
  double weight_heading = 3.0;    ///< per rad of heading error to the goal at the end
  double weight_clearance = 0.3;  ///< per 1/m of the smallest separation (capped)
  double weight_speed = 0.2;      ///< per m/s of |v - desired_speed| at the end
};

/// The Frenet lattice planner of Werling et al. 2010 (docs/baselines.md, "lattice";
/// docs/baselines_sampling.md).
struct LatticeSettings {
  double min_duration = 3.0;   ///< s: the shortest sampled manoeuvre duration
  double max_duration = 5.0;   ///< s: the longest, also the horizon every candidate is checked over
  int duration_samples = 3;    ///< durations evenly from min to max
  double offset_spread = 0.5;  ///< m: end offsets w - spread, w, w + spread besides 0 and w
  double speed_step = 1.0;     ///< m/s between sampled end speeds
  int speed_samples = 7;       ///< end speeds centred on the current speed
  double desired_speed = 40.0 / 3.6;  ///< m/s
  double margin = 0.3;                ///< m the ego's box keeps from every predicted car
  /// Also keep Eq. 1's safe distances (scene.safe_distance) to the target
  /// lane's cars wherever the body is in that lane, as the expert does.
  bool keep_safe_distances = true;
  double max_curvature = 0.2;        ///< 1/m
  double max_heading = 0.35;         ///< rad from the road's direction
  double weight_jerk = 0.1;          ///< per (m/s^3)^2 s, on each axis's jerk integral
  double weight_duration = 0.1;      ///< per s of duration, on each axis
  double weight_offset = 1.0;        ///< per m^2 of end offset from the target-lane centre
  double weight_speed = 1.0;         ///< per (m/s)^2 of end speed from desired_speed
  double weight_lateral = 1.0;       ///< the lateral cost's weight in the sum
  double weight_longitudinal = 1.0;  ///< the longitudinal cost's weight in the sum
};

/// The learned-strategy planner (docs/strategy.md, "strategy-qp").
struct StrategyQpSettings {
  int candidates = 5;  ///< predicted strategies per plan (MLOPT's top k)
  /// Where a plan has no last plan's modes to go on (open loop, a rollout's
  /// first step), the vote ranks this many strategies, and the first
  /// `candidates` of them that lane_modes_can_hold does not refuse at their
  /// first linearization are the plan's candidates: a vote the reachable
  /// states rule out then costs no QP and takes no place. At most
  /// `candidates`: no check (docs/strategy.md).
  int vote_pool = 15;
  /// Where the last plan's modes go first (a re-plan in closed loop), the
  /// votes screened beside them: alternatives to a plan that held a step
  /// ago. 3 instead of `candidates`' 5 takes a sixth off the median planned
  /// step (0.56 -> 0.46 ms) with the same closed-loop success
  /// (docs/strategy.md). At least 1.
  int replan_candidates = 3;
  /// Rank the candidates by one QP each at the first round's linearization,
  /// run the rounds for them in that order and follow the first that
  /// converges collision-free: about one candidate's rounds per plan.
  bool screen = true;
  /// With the screen: the rounds run until this many candidates converged
  /// collision-free, and the cheapest of them is followed. 1 is about 35%
  /// faster per plan (a median cost 1.007 of the optimum against 1.004-1.006)
  /// but drove into 2 at-fault collisions in 500 closed-loop rollouts where 2
  /// drove into none (docs/strategy.md).
  int screen_keep = 2;
  /// Screen with rough QPs (FixedModeSettings::rough): about half the
  /// iterations, and only the ranking depends on them.
  bool rough_screen = true;
  /// Where a rough screen QP stops (complementarity, rows and slack): 1e-2
  /// takes about a sixth fewer iterations per plan than 1e-3, at a median
  /// cost 0.0002 higher (docs/strategy.md). In (0, 1).
  double screen_tolerance = 1e-2;
  /// Stop a candidate's screen QP once its lower bound passes the cheapest
  /// screened so far (MiqpSettings::objective_cutoff): it ranks after it
  /// either way.
  bool screen_cutoff = true;
  /// Once a candidate holds, a later one runs its rounds only if its
  /// screened cost is below the held plan's: its first round already costs
  /// more, and with screen_keep 2 that runner-up was most of the plan's QPs.
  bool skip_dearer = true;
  /// Once a plan holds, also try the strategies whose two switch nodes (out
  /// of the ego lane, into the target lane) each lie within this many nodes
  /// of the followed one's, each screened with the plan's cost as cutoff and
  /// its rounds run where the screen is cheaper: the vote often lands a node
  /// or two off the optimum's strategy. 0: off.
  int neighbour_nodes = 0;
  /// Where a plan has no path to start from (open loop, a rollout's first
  /// step), start each candidate's rounds from the warm start with its lane
  /// change timed to the candidate's switch nodes (warm_start_for_modes)
  /// rather than the expert's, timed to the middle of the horizon.
  bool timed_warm_start = true;
  /// Without the screen: follow the first candidate that holds in the
  /// model's order (CoCo) instead of the cheapest of all (MLOPT).
  bool first_feasible = false;
  /// A strategy is a gap and its lane modes. The votes go first to one gap:
  /// the last plan's, else Eq. 1's (beside the ego). Where none of them
  /// holds, this many other gaps around the ego get `replan_candidates` votes
  /// each, in the order in which they open (learn::gap_open_time), before
  /// the exact search. 0: one gap, as under expert.gap = fixed.
  int other_gaps = 2;
};

/// How the other cars treat the car ahead of them (docs/traffic.md).
/// How another car moves (docs/traffic.md). Replay: exactly as recorded,
/// ignoring everything (a scene cut from a recording, docs/recorded.md).
enum class Behavior { ConstantSpeed, ConstantAccel, Idm, Replay };

struct TrafficSettings {
  /// A car of constant speed or acceleration follows the car ahead in its
  /// lane (the ego included once its body is there) where its behavior would
  /// bring it closer than Krauss's safe speed allows, as SUMO's default car
  /// does; false: the paper's traffic, whose cars ignore everything and may
  /// drive through each other.
  bool followers_react = true;
  double reaction_time = 1.0;  ///< s: Krauss's tau, SUMO's default
  double follow_decel = 4.5;   ///< m/s^2: Krauss's b, the braking a follower plans with (SUMO's)
  /// m, bumper to bumper: the gap a following car keeps on top of Krauss's
  /// safe-speed gap (SUMO's minGap; the SUMO loop takes its cars' own).
  double min_gap = 0.0;
  /// When a car starts to follow an ego that changes into its lane.
  SeesEgo sees_ego = SeesEgo::InLane;
  /// m/s^2: no car brakes harder, whatever its model asks (dry asphalt allows
  /// about 8 to 9); where that is not enough, the collision happens and is
  /// judged. None (JSON null): no limit, the paper's IDM.
  std::optional<double> max_decel = 9.0;
  /// How the planners predict a replayed car: never by its recorded future,
  /// which no planner may know.
  Behavior replay_prediction = Behavior::ConstantSpeed;
};

struct Config {
  std::string preset = "paper";
  double lane_width = 3.75;  ///< m
  VehicleSize vehicle;
  Limits limits;
  IdmParameters idm;
  /// m/s: a constant-acceleration car speeding up stops accelerating here
  /// (the paper's traffic stays within 60 km/h); none (JSON null): no cap.
  /// Never the ego's bound, and never applied to a car already faster.
  std::optional<double> traffic_max_speed = 60.0 / 3.6;
  TrafficIntegration traffic_integration = TrafficIntegration::Ballistic;
  TrafficSettings traffic;
  SafetyMargins safety;
  ExpertSettings expert;
  LabelTolerances labels;
  SamplerSettings sampler;
  ClosedLoopSettings closed_loop;
  MpcSettings mpc;
  DwaSettings dwa;
  LatticeSettings lattice;
  StrategyQpSettings strategy_qp;

  [[nodiscard]] double dt() const { return expert.horizon / expert.steps; }
  /// Throws InputError when a value is non-finite or out of its physical range.
  void validate() const;
};

/// Named presets: "paper" (the default) and "authors" (the public MATLAB code).
[[nodiscard]] Config make_preset(std::string_view name);
/// The paper's traffic: cars that ignore everything, IDM without a braking
/// limit. The `authors` preset's, and the reproduction's (docs/traffic.md).
[[nodiscard]] TrafficSettings paper_traffic();
/// `config` with the paper's own formulation: Eq. 1's one gap and distances
/// (`expert.gap = fixed`, no cut-in rule) in the paper's traffic. What the
/// reproduction of the paper's tables runs (docs/experiments.md).
[[nodiscard]] Config paper_formulation(Config config);
[[nodiscard]] std::vector<std::string> preset_names();

void to_json(nlohmann::json& out, const Config& config);
/// A config as JSON (to_json's) without the sections that only the
/// comparison planners read (mpc, dwa, lattice, strategy_qp): what expert
/// data and the models trained on them depend on. Data sets and models are
/// matched on this, so that tuning or adding a planner setting does not
/// orphan them.
[[nodiscard]] nlohmann::json expert_data_config(nlohmann::json config);
/// Starts from the preset named in the file (or "paper") and overrides the
/// fields present. Unknown keys are an error, so typos do not pass silently.
[[nodiscard]] Config config_from_json(const nlohmann::json& in);
[[nodiscard]] Config load_config(const std::string& path);
void save_config(const Config& config, const std::string& path);

}  // namespace lanechange
