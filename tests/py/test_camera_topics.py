"""The sim's camera topics (`camera/<name>/image_raw`, `camera/<name>/camera_info`), seen live by
a cyclonedds subscriber and read back from the recorded bag by `rosbags` and `mcap`: type,
encoding, size, intrinsics, one image per step stamped exactly as that step's observation; and a
bad camera name refused at start-up with the valid ones named.

Only run inside scripts/netns-isolate."""

# No `from __future__ import annotations`: cyclonedds resolves annotations at runtime.
import math
import os
import subprocess
import time

import numpy as np
import pytest

import node_suite
from node_suite import Launched, ns_of
from test_recorder import RecordingAgent, bag_messages

TASK = "IIWA/box/no_obstacle/pick_place"
NS = "/cam"
CAMERAS = {"frontview": 45.0, "eye_in_hand": 75.0}  # enabled cameras and their fovy (deg)
WIDTH, HEIGHT = 64, 48
STEPS = 12
PARAMS = f"""/**/sim:
  ros__parameters:
    cameras: [{", ".join(CAMERAS)}]
    camera_width: {WIDTH}
    camera_height: {HEIGHT}
"""


class CameraAgent(RecordingAgent):
    def __init__(self, launched: Launched):
        super().__init__(launched)
        self.images = {c: self.agent.subscribe(f"camera/{c}/image_raw", "sensor_msgs/msg/Image") for c in CAMERAS}
        self.infos = {c: self.agent.subscribe(f"camera/{c}/camera_info", "sensor_msgs/msg/CameraInfo")
                      for c in CAMERAS}


@pytest.fixture(scope="module")
def cameras(tmp_path_factory):
    """One recorded episode of STEPS steps with two cameras on: what the agent saw, the bag."""
    log_dir = tmp_path_factory.mktemp("cameras")
    params = log_dir / "cameras.yaml"
    params.write_text(PARAMS)
    bag = log_dir / "bag"
    launched = Launched(log_dir, NS, TASK, "--record", str(bag), "--params-file", str(params))
    agent = CameraAgent(launched)
    try:
        agent.wait_until_recorded()
        for c in CAMERAS:
            agent.images[c].wait_for_publishers(timeout=20)
            agent.infos[c].wait_for_publishers(timeout=20)
            launched.wait_for_log(f"recording {NS}/camera/{c}/image_raw ")
            launched.wait_for_log(f"recording {NS}/camera/{c}/camera_info ")
        time.sleep(0.5)
        reply = agent.reset(seed=3)
        since = ns_of(reply.observation.header.stamp)
        for k in range(STEPS):
            agent.step([q + 0.05 * ((k % 5) - 2) for q in agent.home])
        agent.statuses.wait_for(agent.this_episode(STEPS), timeout=5)
        for c in CAMERAS:
            agent.images[c].wait_for(lambda m: ns_of(m.header.stamp) >= ns_of(
                agent.observations.samples[-1].header.stamp), timeout=10)
        time.sleep(0.3)
        seen = {
            "observation": [o for o in agent.observations.samples if ns_of(o.header.stamp) >= since],
            "images": {c: [m for m in agent.images[c].samples if ns_of(m.header.stamp) >= since] for c in CAMERAS},
            "infos": {c: [m for m in agent.infos[c].samples if ns_of(m.header.stamp) >= since] for c in CAMERAS},
        }
    finally:
        agent.agent.close()
        launched.stop()
    assert f"cameras [{', '.join(CAMERAS)}]" in launched.text()
    return {"bag": bag, "since": since, "seen": seen}


def focal(fovy_deg: float) -> float:
    return 0.5 * HEIGHT / math.tan(math.radians(fovy_deg) / 2)


def check_image(image, camera: str) -> np.ndarray:
    assert (image.encoding, image.width, image.height, image.step, image.is_bigendian) == (
        "rgb8", WIDTH, HEIGHT, 3 * WIDTH, 0)
    assert image.header.frame_id == f"{camera}_optical_frame"
    raw = image.data
    if isinstance(raw, (bytes, bytearray, memoryview)):
        data = np.frombuffer(bytes(raw), dtype=np.uint8)
    else:  # a list (cyclonedds) or a numpy array (rosbags)
        data = np.asarray(raw, dtype=np.uint8)
    assert data.size == WIDTH * HEIGHT * 3
    return data.reshape(HEIGHT, WIDTH, 3)


def check_info(info, camera: str) -> None:
    assert (info.width, info.height, info.distortion_model) == (WIDTH, HEIGHT, "plumb_bob")
    assert info.header.frame_id == f"{camera}_optical_frame"
    f = focal(CAMERAS[camera])
    np.testing.assert_allclose(list(info.k), [f, 0, WIDTH / 2, 0, f, HEIGHT / 2, 0, 0, 1], rtol=1e-12)
    np.testing.assert_allclose(list(info.p), [f, 0, WIDTH / 2, 0, 0, f, HEIGHT / 2, 0, 0, 0, 1, 0], rtol=1e-12)
    assert list(info.r) == [1, 0, 0, 0, 1, 0, 0, 0, 1] and list(info.d) == [0.0] * 5


def test_every_step_has_one_image_per_camera_stamped_as_its_observation(cameras):
    seen = cameras["seen"]
    stamps = [ns_of(o.header.stamp) for o in seen["observation"]]
    assert len(stamps) == STEPS + 1, "the reset and every step"
    for camera in CAMERAS:
        images, infos = seen["images"][camera], seen["infos"][camera]
        assert [ns_of(m.header.stamp) for m in images] == stamps, camera
        assert [ns_of(m.header.stamp) for m in infos] == stamps, camera
        frames = [check_image(m, camera) for m in images]
        for info in infos:
            check_info(info, camera)
        # Something is in view: not one flat colour.
        assert all(len(np.unique(f.reshape(-1, 3), axis=0)) > 10 for f in frames)
    # The arm moves: the wrist camera's view changes from step to step; the world camera sees it too.
    wrist = [check_image(m, "eye_in_hand") for m in seen["images"]["eye_in_hand"]]
    assert not np.array_equal(wrist[0], wrist[-1])
    front = [check_image(m, "frontview") for m in seen["images"]["frontview"]]
    assert not np.array_equal(front[0], front[-1])


def test_the_images_are_in_the_bag_as_sent(cameras):
    """rosbags (checking the embedded definitions' hashes) and the mcap reader with its ROS 2
    decoder read the camera topics; what they hold equals what the subscriber got."""
    recorded = bag_messages(cameras["bag"])
    since = cameras["since"]
    observations = [m for _, m in recorded[f"{NS}/observation"] if ns_of(m.header.stamp) >= since]
    for camera in CAMERAS:
        images = [m for _, m in recorded[f"{NS}/camera/{camera}/image_raw"] if ns_of(m.header.stamp) >= since]
        infos = [m for _, m in recorded[f"{NS}/camera/{camera}/camera_info"] if ns_of(m.header.stamp) >= since]
        assert [ns_of(m.header.stamp) for m in images] == [ns_of(o.header.stamp) for o in observations]
        assert len(infos) == len(images)
        live = cameras["seen"]["images"][camera]
        for got, sent in zip(images, live):
            assert np.array_equal(check_image(got, camera), check_image(sent, camera))
        for info in infos:
            check_info(info, camera)

    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    counted = {}
    for path in sorted(cameras["bag"].glob("*.mcap")):
        with path.open("rb") as f:
            reader = make_reader(f, decoder_factories=[DecoderFactory()])
            for schema, channel, _, decoded in reader.iter_decoded_messages(
                    topics=[f"{NS}/camera/{c}/image_raw" for c in CAMERAS]):
                assert schema.name == "sensor_msgs/msg/Image"
                assert (decoded.encoding, decoded.width, decoded.height) == ("rgb8", WIDTH, HEIGHT)
                assert len(decoded.data) == WIDTH * HEIGHT * 3
                counted[channel.topic] = counted.get(channel.topic, 0) + 1
    assert counted == {f"{NS}/camera/{c}/image_raw": len(recorded[f"{NS}/camera/{c}/image_raw"]) for c in CAMERAS}


@pytest.mark.parametrize("value, says", [
    ("[front]", "unknown camera `front`; valid cameras: frontview, agentview, birdview, sideview, eye_in_hand"),
    ("[birdview, birdview]", "listed twice"),
])
def test_a_bad_camera_parameter_stops_the_sim_naming_what_is_valid(value, says):
    node_suite.require_isolation()
    result = subprocess.run(
        [str(node_suite.node_dir() / "sim_node"), "--ros-args", "-r", "__ns:=/badcam", "-p", f"cameras:={value}"],
        env=dict(os.environ, ROS_DOMAIN_ID=str(node_suite.random_domain())), capture_output=True, text=True, timeout=30)
    assert result.returncode != 0
    assert says in result.stderr, result.stderr
    size = subprocess.run(
        [str(node_suite.node_dir() / "sim_node"), "--ros-args", "-p", "camera_width:=0"],
        env=dict(os.environ, ROS_DOMAIN_ID=str(node_suite.random_domain())), capture_output=True, text=True, timeout=30)
    assert size.returncode != 0 and "1 to 4096" in size.stderr, size.stderr


def test_rclpy_reads_the_camera_topics(tmp_path):
    """Real rclpy (Jazzy, Fast DDS) subscribes to a camera's image with the sensor-data profile (best
    effort, what image viewers use) and to its camera_info with the default one, then resets through
    the service: both arrive stamped as the reset's observation, rgb8 of the configured size."""
    from composuite_msgs.srv import Reset
    from rclpy.qos import qos_profile_sensor_data
    from sensor_msgs.msg import CameraInfo, Image

    from rclpy_agent import RclpyAgent

    params = tmp_path / "cameras.yaml"
    params.write_text(PARAMS)
    with node_suite.launch_running(tmp_path, "/camrp", TASK, "--params-file", str(params),
                                   service_mapping="fastdds") as launched:
        agent = RclpyAgent(launched.domain)
        try:
            images, infos = [], []
            agent.node.create_subscription(Image, "/camrp/camera/frontview/image_raw", images.append,
                                           qos_profile_sensor_data)
            agent.node.create_subscription(CameraInfo, "/camrp/camera/frontview/camera_info", infos.append, 10)
            reset = agent.node.create_client(Reset, "/camrp/reset")
            agent.spin_until(lambda: agent.node.count_publishers("/camrp/camera/frontview/image_raw") == 1,
                             what="the image publisher")
            time.sleep(0.5)  # our readers matched on the sim's side too
            reply = agent.call(reset, Reset.Request(seed=2, use_seed=True))
            stamp = ns_of(reply.observation.header.stamp)
            image = agent.spin_until(lambda: next((m for m in images if ns_of(m.header.stamp) == stamp), None),
                                     what="the reset's image")
            info = agent.spin_until(lambda: next((m for m in infos if ns_of(m.header.stamp) == stamp), None),
                                    what="the reset's camera_info")
        finally:
            agent.close()
    assert (image.encoding, image.width, image.height, image.step) == ("rgb8", WIDTH, HEIGHT, 3 * WIDTH)
    assert len(image.data) == WIDTH * HEIGHT * 3
    assert (info.width, info.height) == (WIDTH, HEIGHT)
    assert info.k[0] == pytest.approx(focal(CAMERAS["frontview"]), rel=1e-12)
