"""A controller for MuJoCo's own car (tests/data/mjcf/mujoco_car.xml, google-deepmind/mujoco
model/car/car.xml): the planner's (v, w) into its two tendon motors, `forward` and `turn`."""

RADIUS, TRACK = 0.03, 0.12     # the wheels' radius and the distance between them (m)
DAMPING, GAIN = 0.06, 0.02     # control per rad/s: what the joints' damping takes, the integral gain


class Car:
    """A speed loop on each tendon (its velocity: the wheels' mean speed, or half their
    difference, rad/s): the damping the target speed needs, plus the integrated speed error (the
    slope's load), at the control rate."""

    def reset(self, model, data):
        self.tendons = [model.tendon("forward").id, model.tendon("turn").id]
        self.acts = [model.actuator("forward").id, model.actuator("turn").id]
        self.held = [0.0, 0.0]

    def control(self, command, model, data):
        v, _, w = command
        ctrl = [0.0] * model.nu
        for i, want in enumerate((v / RADIUS, w * TRACK / 2 / RADIUS)):
            self.held[i] += GAIN * (want - data.ten_velocity[self.tendons[i]])
            ctrl[self.acts[i]] = DAMPING * want + self.held[i]
        return ctrl
