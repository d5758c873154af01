// An outside program that uses the installed library: it samples a scenario
// and checks that it reads back the same.
#include <cstdio>
#include <lanechange/sampler.hpp>
#include <lanechange/scenario.hpp>
#include <nlohmann/json.hpp>

int main() {
  const lanechange::ScenarioSampler sampler(lanechange::Config{}, 5);
  const lanechange::Scenario s = sampler.sample(0);
  const auto again =
      lanechange::scenario_from_json(lanechange::scenario_to_json(s), lanechange::Config{});
  if (lanechange::scenario_to_json(again) != lanechange::scenario_to_json(s)) return 1;
  std::printf("consumer ok: ego speed %.3f m/s\n", s.ego.v);
  return 0;
}
