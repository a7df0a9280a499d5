"""Body controllers for the MJCF cart of tests/data/mjcf/cart.xml: the planner's (v, w) into the
two wheels' speed targets, and controllers that break the protocol."""

RADIUS, TRACK = 0.1, 0.4


class Cart:
    """Differential drive: each wheel's speed target (v -+ w track / 2) / r."""

    def reset(self, model, data):
        self.left = model.actuator("left").id
        self.right = model.actuator("right").id
        self.controls = [0.0] * model.nu

    def control(self, command, model, data):
        v, _, w = command
        self.controls[self.left] = (v - w * TRACK / 2) / RADIUS
        self.controls[self.right] = (v + w * TRACK / 2) / RADIUS
        return self.controls


class HoldsStill(Cart):
    """Holds both wheels still whatever the planner asks (a drive that does not follow)."""

    def control(self, command, model, data):
        return super().control((0.0, 0.0, 0.0), model, data)


class WritesCtrl(Cart):
    """Writes data.ctrl itself and returns None."""

    def control(self, command, model, data):
        data.ctrl[:] = super().control(command, model, data)


class TooFew:
    def control(self, command, model, data):
        return [1.0]


class Raises:
    def control(self, command, model, data):
        raise RuntimeError("motor driver offline")


class ReturnsText:
    def control(self, command, model, data):
        return "full ahead"


class Exits:
    def control(self, command, model, data):
        import sys
        sys.exit(3)


class Sleeps(Cart):
    """Sleeps in control() far longer than any tick limit (a controller that hangs)."""

    def control(self, command, model, data):
        import time
        time.sleep(30)


class Interrupts(Cart):
    """Raises its own KeyboardInterrupt (not the user's Ctrl-C)."""

    def control(self, command, model, data):
        raise KeyboardInterrupt("my own")


class Forks(Cart):
    """Starts a child process that outlives its episode."""

    def reset(self, model, data):
        import subprocess
        super().reset(model, data)
        subprocess.Popen(["sleep", "60"])


def make_cart():
    """A zero-argument factory function (accepted as a class is)."""
    return Cart()


from os import fork  # noqa: E402  (a builtin imported into the user's module: refused all the same)
from shutil import rmtree  # noqa: E402,F401  (a standard-library function: refused)
