"""A downstream Python user of attitude_planner's interfaces: imports the service and the action
(generated into attitude_planner's devel space), fills a request and a goal, and round-trips
them through serialization. Exit status 0 only if the fields survive."""
import io
import sys

from attitude_planner.msg import PlanAttitudeManeuverAction, PlanAttitudeManeuverGoal
from attitude_planner.srv import PlanAttitudeManeuver, PlanAttitudeManeuverRequest


def round_trip(message):
    buffer = io.BytesIO()
    message.serialize(buffer)
    copy = type(message)()
    copy.deserialize(buffer.getvalue())
    return copy


request = PlanAttitudeManeuverRequest(duration=12.8, steps=128, scheme="paper")
request.final_attitude.w = 1.0
goal = PlanAttitudeManeuverGoal(duration=4.0, steps=16)
action = PlanAttitudeManeuverAction()
checks = [
    PlanAttitudeManeuver._type == "attitude_planner/PlanAttitudeManeuver",
    round_trip(request).steps == 128 and round_trip(request).scheme == "paper",
    round_trip(goal).duration == 4.0,
    action.action_goal.goal.steps == 0,
]
print("service %s, action %s: %d of %d checks hold"
      % (PlanAttitudeManeuver._type, action._type, sum(checks), len(checks)))
sys.exit(0 if all(checks) else 1)
