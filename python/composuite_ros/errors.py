"""What can go wrong between an agent and the suite, as exceptions that say what to do."""


class SuiteNotRunningError(TimeoutError):
    """Nothing of the suite answered in a namespace in time (names the namespace and what is
    missing)."""


class StepLostError(TimeoutError):
    """A lockstep step's messages did not all arrive in time (names the step and what came)."""


class EpisodeOverError(RuntimeError):
    """`step()` after the episode ended (the reference raises too); call `reset()`."""
