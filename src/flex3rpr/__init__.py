"""flex3rpr: the 3-RPR parallel robot with flexible links, in Python, on the C core.

    import flex3rpr
    sim = flex3rpr.Sim("config/scenes/rest.yaml")
    s = sim.step([10.0, 0, 0, 0, 0, 0])        # 1 ms holding 10 N on leg 1
    print(s.t, s.x_p, s.pose, s.tip_deflection)

Needs no ROS. The generated messages (flex3rpr.msg, flex3rpr.srv) share the name when the catkin
workspace is sourced. docs/python.md has the whole interface.
"""
from ._core import ArgumentError, Error, SceneError
from .sim import Sim, State, scene_path
from .rollouts import rollouts, study
from .env import Flex3rprEnv, tracking_vibration_reward

__all__ = ["ArgumentError", "Error", "SceneError", "Sim", "State", "scene_path", "rollouts", "study", "Flex3rprEnv",
           "tracking_vibration_reward"]
