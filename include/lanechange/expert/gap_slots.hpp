#pragma once
// The gaps of the target lane around the ego in a fixed number of slots, and
// the scene described through them: a view of the same size for any number
// of cars, which the data set labels and a gap classifier learns from
// (docs/dataset.md, "Gaps").
#include <array>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "lanechange/expert/formulation.hpp"
#include "lanechange/scenario.hpp"

namespace lanechange::expert {

/// Slot kGapSlotBeside is the gap the ego stands beside at t = 0: behind
/// every target-lane car ahead of its centre and ahead of every other one.
/// The slots below it are the gaps behind, those above the gaps ahead.
inline constexpr int kGapSlots = 5;
inline constexpr int kGapSlotBeside = 2;

/// Where a car that frames no gap is put in the features: as far as the
/// longest safe distance of the sampled scenes and more, so a gap open on
/// that side reads as a very long one.
inline constexpr double kOpenGapDistance = 200.0;  // m

struct GapSlots {
  /// The gap in each slot, none where the lane has no gap that far out.
  std::array<std::optional<Gap>, kGapSlots> gaps;
  /// The slot of the gap framed by the same cars as `gap`, or -1 when it is
  /// in none (further out than the slots reach).
  [[nodiscard]] int slot_of(const Gap& gap) const;
};

/// The slots of a scene, from its cars at t = 0.
[[nodiscard]] GapSlots gap_slots(const Scenario& scenario);

/// A slot's name in column names: "m2", "m1", "0", "p1", "p2".
[[nodiscard]] std::string_view gap_slot_name(int slot);

/// The names of gap_features' values, in order.
[[nodiscard]] const std::vector<std::string>& gap_feature_names();
/// The scene at t = 0 relative to the ego: its speed and acceleration; the
/// nearest ego-lane cars ahead and behind; and for each slot the two cars
/// that frame its gap (distance ahead of the ego, speed relative to it,
/// acceleration). A side without a car reads kOpenGapDistance away at the
/// ego's speed; a slot without a gap reads as a gap of no length that far
/// out, behind or ahead.
[[nodiscard]] std::vector<double> gap_features(const Scenario& scenario, const GapSlots& slots);

/// The two cars that frame the gap a lane change drives to; none where the
/// gap is open that way.
struct GapFrame {
  std::optional<CarIndex> behind, ahead;
  bool operator==(const GapFrame&) const = default;
};
[[nodiscard]] inline GapFrame frame_of(const Gap& gap) {
  return {gap.car_behind(), gap.car_ahead()};
}

/// What a network that drives to one gap sees of the traffic at an instant,
/// relative to the ego: the gap's two framing cars and the nearest car ahead
/// in the ego lane, each as distance ahead, speed relative to the ego and
/// acceleration (an open side reads as gap_features reads it). The same
/// nine numbers for any number of cars.
inline constexpr std::size_t kGapViewSize = 9;
[[nodiscard]] const std::vector<std::string>& gap_view_names();
/// `cars`: every car of `scene` as it stands now, in the scene's order.
[[nodiscard]] std::array<double, kGapViewSize> gap_view(const Scenario& scene,
                                                        std::span<const CarState> cars,
                                                        const EgoState& ego, const GapFrame& frame);

}  // namespace lanechange::expert
