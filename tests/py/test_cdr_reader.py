"""composuite_ros._cdr.FieldReader, which the Gymnasium package uses to read the observation,
reward and episode status of every step from their CDR bytes: what it reads equals what rclpy's
own deserialisation gives, for messages serialised by rclpy (no DDS involved)."""

import numpy as np
import pytest
from composuite_msgs.msg import EpisodeStatus, StagedReward, TaskSpec
from rclpy.serialization import serialize_message

from composuite_ros._cdr import FieldReader
from composuite_ros._link import RewardView, StatusView

# Names of every length modulo 4, an empty one and non-ASCII: each string is 4-aligned after the
# one before, so every padding case is crossed.
NAMES = [["reach", "grasp", "lift", "hover", "place"], ["a", "bc", "def", "ghij", ""],
         ["größe"], []]


@pytest.mark.parametrize("names", NAMES)
def test_reward_fields_equal_rclpys(names):
    message = StagedReward(episode=7, step=123, objective="pick_place", stage_names=names,
                           stage_values=[0.1 * k for k in range(len(names))],
                           stage_maxima=[1.0] * len(names), current_stage=len(names) - 1,
                           total=0.4375, success=True)
    view = RewardView.of_bytes(serialize_message(message))
    assert (view.episode, view.step, view.current_stage, view.total, view.success) == (
        7, 123, len(names) - 1, 0.4375, True)
    assert view.stage_names == names
    assert np.array_equal(view.stage_values, np.array(message.stage_values))


def test_status_fields_equal_rclpys():
    message = EpisodeStatus(task=TaskSpec(robot="IIWA", object="box", obstacle="no_obstacle",
                                          objective="push"),
                            seed=2**40 + 3, episode=4, step=500, horizon=500, done=True,
                            terminated=False, truncated=True, reason=EpisodeStatus.REASON_HORIZON,
                            reason_text="the horizon of 500 steps was reached",
                            episode_return=12.5, success_seen=True)
    view = StatusView.of_bytes(serialize_message(message))
    assert view == StatusView(episode=4, step=500, done=True, terminated=False, truncated=True,
                              reason_text="the horizon of 500 steps was reached")


def test_a_truncated_message_is_refused_by_name():
    data = serialize_message(StagedReward(stage_names=["reach", "grasp"], stage_values=[0.5, 0.25]))
    reader = FieldReader(StagedReward, ["stage_names", "stage_values"])
    assert reader.read(data)["stage_names"] == ["reach", "grasp"]
    # Cut inside the header's frame_id length, and inside stage_values (rclpy's serialised
    # message may carry padding after its last field, so cutting the tail proves nothing).
    for cut in (12, 4 + 70):
        with pytest.raises(ValueError, match="message ends at byte"):
            reader.read(data[:cut])
    with pytest.raises(ValueError, match="no field"):
        FieldReader(StagedReward, ["stage_labels"])
