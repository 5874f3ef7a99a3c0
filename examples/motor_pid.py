"""Run the deliverable's speed-PID experiment (Figure 25) and print its step-response figures."""

import dataclasses

import firefleet

scenario = firefleet.load_scenario("motor-pid")  # a built-in name, or a path to a YAML file
team = dataclasses.replace(scenario, poses=((0.0, 0.0, 0.0),) * 3)  # three robots, one run
result = firefleet.simulate(team, seed=1)  # same seed, same arrays
m = firefleet.compute_metrics(result)
print(f"rise {m['rise_time_s']:.3f} s, settling {m['settling_time_s']:.3f} s")
print(f"overshoot {m['overshoot_pct']:.1f} %, load recovery {m['disturbance_recovery_s']:.3f} s")
print("wheel speeds (T, N, 2):", result.wheel_speed_rad_s.shape)
