"""The seed's rest-to-rest slew (seed 000, Fig. 1) as a planning request or goal: one place for the
ROS timing scripts (action_timing.py, service_latency.py)."""
import math


def fill_seed(r, steps):
    """Fills a PlanAttitudeManeuver request or goal `r` with the seed's slew at N = `steps`."""
    r.inertia = [13.25, -7.80, -11.40, -7.80, 16.25, 4.71, -11.40, 4.71, 18.37]
    r.allow_nonphysical_inertia = True
    r.initial_attitude.w = 1.0
    r.final_attitude.w = math.cos(math.pi / 6)
    r.final_attitude.x = math.sin(math.pi / 6)
    r.duration = 12.8
    r.steps = steps
    return r
