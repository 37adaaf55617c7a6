"""What differs between the Gymnasium versions the package takes (1.0 up to 2)."""

try:
    from gymnasium.vector import AutoresetMode

    # The vector envs' metadata key saying how they reset (Gymnasium 1.1 on).
    NEXT_STEP_AUTORESET = {"autoreset_mode": AutoresetMode.NEXT_STEP}
except ImportError:
    # Gymnasium 1.0 (which d3rlpy 2.8 pins) has no such key: every vector env resets on the
    # step after an episode ends, as ours do.
    NEXT_STEP_AUTORESET = {}
