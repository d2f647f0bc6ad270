"""Movement models for the simulator tests, learned from a synthetic demonstration."""

import numpy as np

from wipelab.learning import learn_offline


def circle_model(frequency_hz: float = 1.0, radius: float = 0.1, seed: int = 0):
    """A circular wipe (radius m) demonstrated at ``frequency_hz`` somewhere in a camera's world
    frame, tracked at 30 Hz with 2 mm noise, learned offline."""
    rng = np.random.default_rng(seed)
    t = np.arange(0, 8.0, 1 / 30)
    phase = 2 * np.pi * frequency_hz * t
    xy = np.column_stack([1.3 + radius * np.cos(phase), 0.4 + radius * np.sin(phase)])
    model, _ = learn_offline(t, xy + rng.normal(scale=0.002, size=xy.shape), dofs=("x", "y"))
    return model
