"""An environment for learning and tuning, in the shape of Gymnasium's API (reset(seed) ->
(observation, info); step(action) -> (observation, reward, terminated, truncated, info)). It
needs no Gymnasium; where Gymnasium is installed it is registered as "Flex3rpr-v0"."""
import numpy as np

from ._core import Error
from .sim import Sim, scene_path


def tracking_vibration_reward(state, target, action, weights=(1e4, 1e6, 1e-6)):
    """The default reward: minus (w_track |pose - target|^2 + w_vib sum w_tip^2 + w_effort
    |action|^2), with the pose's angle in rad weighted as metres and the tip deflections w_i(l)
    in m: tracking plus vibration, with a little effort. Replace it with any function of the
    same arguments."""
    w_track, w_vib, w_effort = weights
    error = state.pose - target
    return -(w_track * float(error @ error) + w_vib * float(state.tip_deflection @
                                                               state.tip_deflection)
             + w_effort * float(np.dot(action, action)))


class Flex3rprEnv:
    """The robot as an environment: an action is the six actuator efforts (leg forces in N,
    cylinder torques in N m) held for one period; the observation is what a controller sees:
    the scene's sensors' readings when it has sensors (encoders, root strain gauges,
    accelerometer: noisy, quantised, delayed), else the joint positions (rho, theta), the
    platform pose and twist and the tip deflections and their rates (`observation_names` names
    them). An episode ends (terminated) when
    the physics stops (a leg collapsed, a singular pose: info["reason"] says which) or the pose
    leaves `limit` (m from the target), and is truncated after `horizon` periods.

    target: the platform pose (x, y, phi) to track; start: the pose reset() starts from (its
    jitter in m and rad with the seed: start_noise). The default scene is the package's
    rest_turned.yaml, found from any directory: the platform turned 0.3 rad off the singular
    home pose, with end stops.

    Spaces: an action is clipped to +-action_limit (N and N m; 200 by default) before it is
    applied, and action_space says so; observation_space is unbounded. After an episode has
    terminated or been truncated, step() raises RuntimeError until reset()."""

    metadata = {"render_modes": []}

    def __init__(self, scene=None, target=(0.01, 0.0, 0.0), horizon=500,
                 period=1e-3, reward=tracking_vibration_reward, start=None, start_noise=0.0,
                 limit=0.05, action_limit=200.0, overrides=None):
        self.sim = Sim(scene_path("rest_turned.yaml") if scene is None else scene,
                       overrides=overrides, period=period)
        self._ended = False
        self.target = np.asarray(target, dtype=float)
        self.horizon, self.reward_fn, self.limit = int(horizon), reward, float(limit)
        self.start = None if start is None else np.asarray(start, dtype=float)
        self.start_noise = float(start_noise)
        self.action_limit = float(action_limit)
        self.k = 0
        self.rng = np.random.default_rng()
        names = self.sim.columns
        self._obs_index = np.array(
            [names.index(n) for n in ("rho_1", "rho_2", "rho_3", "theta_1", "theta_2", "theta_3",
                                      "x_p", "y_p", "phi_p", "x_p_dot", "y_p_dot", "phi_p_dot",
                                      "w_tip_1", "w_tip_2", "w_tip_3", "w_tip_1_dot",
                                      "w_tip_2_dot", "w_tip_3_dot")])
        self.observation_names = self.sim.sensor_names or [names[i] for i in self._obs_index]
        self.action_names = ["leg_force_1", "leg_force_2", "leg_force_3", "cylinder_torque_1",
                             "cylinder_torque_2", "cylinder_torque_3"]
        try:  # the spaces where Gymnasium is installed
            from gymnasium import spaces
            self.action_space = spaces.Box(-self.action_limit, self.action_limit, (6,))
            self.observation_space = spaces.Box(-np.inf, np.inf, (len(self.observation_names),))
        except ImportError:
            self.action_space = self.observation_space = None

    def _observe(self, state):
        if self.sim.sensor_names:
            return self.sim.sensors
        return state.vector[self._obs_index].copy()

    def reset(self, seed=None, options=None):
        if seed is not None:
            self.rng = np.random.default_rng(seed)
        self.sim.reset()
        self.k = 0
        self._ended = False
        if self.start is not None or self.start_noise > 0.0:
            base = self.sim.state.pose.copy() if self.start is None else self.start
            self.sim.set_state(base + self.start_noise * self.rng.standard_normal(3))
        return self._observe(self.sim.state), {"t": self.sim.t}

    def step(self, action):
        if self._ended:
            raise RuntimeError("Flex3rprEnv.step: the episode has ended (terminated or truncated); "
                               "call reset()")
        action = np.clip(np.asarray(action, dtype=float), -self.action_limit, self.action_limit)
        info = {"reason": ""}
        try:
            state = self.sim.step(action)
        except Error as e:
            state = self.sim.state
            info["reason"] = "physics: " + str(e)
            self._ended = True
            return self._observe(state), self.reward_fn(state, self.target, action), True, \
                False, info
        self.k += 1
        reward = self.reward_fn(state, self.target, action)
        terminated = bool(np.max(np.abs(state.pose[:2] - self.target[:2])) > self.limit)
        if terminated:
            info["reason"] = "limit: the pose left %g m of the target" % self.limit
        truncated = not terminated and self.k >= self.horizon
        if truncated:
            info["reason"] = "horizon: %d periods" % self.horizon
        info["t"] = state.t
        self._ended = terminated or truncated
        return self._observe(state), reward, terminated, truncated, info

    def close(self):
        pass


try:  # registered with Gymnasium where it is installed; nothing needs it
    import gymnasium

    gymnasium.register(id="Flex3rpr-v0", entry_point="flex3rpr.env:Flex3rprEnv")
except Exception:  # ImportError, or registered already
    pass
