"""Goal choosers written in Python for the tests (afford.GoalChooser)."""
import afford


def silhouette(image):
    return (image > 0).any(axis=2)


class PyColours(afford.GoalChooser):
    """Colour goals on the objects it saw, from the colour changes it saw; explorations first and when it has none."""

    kind = "py-colours"

    def __init__(self, config):
        super().__init__(config)
        self.objects = {}   # rounded place -> (image, x, y), as last seen
        self.outcomes = []  # images objects took after a colour change
        self.reached = 0

    def saw_object(self, step, image, x, y):
        self.objects[(round(x, 3), round(y, 3))] = (image.copy(), x, y)

    def saw_effect(self, effect):
        if not effect["affordance"]:
            return
        bx, by = effect["before"]
        self.objects.pop((round(bx, 3), round(by, 3)), None)
        ax, ay = effect["after"]
        self.objects[(round(ax, 3), round(ay, 3))] = (effect["after_image"].copy(), ax, ay)
        if effect["action"] != 0 and not any((effect["after_image"] == o).all() for o in self.outcomes):
            self.outcomes.append(effect["after_image"].copy())

    def attempted(self, attempt):
        self.reached += attempt["reached"]

    def next(self, step, id):
        rng = afford.KeyedRng(self.config["seed"], step, id)
        if id < 20:
            return afford.Goal("explore", action=rng.integer(4))
        pairs = [(o, c) for o in self.objects.values() for c in self.outcomes
                 if (silhouette(o[0]) == silhouette(c)).all() and (o[0] != c).any()]
        if not pairs:
            return afford.Goal("explore", action=rng.integer(4, 1))
        (image, x, y), c = pairs[rng.integer(len(pairs), 2)]
        return {"module": "colour", "object_x": x, "object_y": y, "x": x, "y": y, "image": c}


class OutOfPlace(afford.GoalChooser):
    """A goal whose place is outside the scene: the run fails naming the field."""

    kind = "out-of-place"

    def next(self, step, id):
        return afford.Goal("move", 0.5, 0.5, 1.5, 0.5, [[[0, 0, 0]] * 21] * 21)


class Raises(afford.GoalChooser):
    """A chooser whose next() raises: the run fails, its trace said once."""

    kind = "raises"

    def next(self, step, id):
        raise ValueError("no goal here")
