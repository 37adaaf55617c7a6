"""Videos of recorded episodes, made from the bag alone: `composuite bag render` (GIF in-process,
MP4 through ffmpeg) and `composuite session --video`, read back by readers nobody here wrote:
Pillow for GIF, imageio with the ffmpeg of the imageio-ffmpeg wheel for MP4. One frame per
recorded observation (the episode's start, then every step), counted in the bag with rosbags.

Only run inside scripts/netns-isolate (the session speaks DDS)."""

import csv
from pathlib import Path

import imageio.v3 as iio
import imageio_ffmpeg
import numpy as np
import pytest
from PIL import Image, ImageSequence

from test_recorder import bag_messages, composuite
from test_session import session

TASKS = ["Panda/box/no_obstacle/push", "IIWA/plate/object_wall/shelf"]
HORIZON = 12


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """A two-task session of two episodes each with --video: its directory and the observations
    the bag holds per episode."""
    out = tmp_path_factory.mktemp("render") / "s"
    result = session("--tasks", *TASKS, "--episodes", "2", "--policy", "random", "--horizon", str(HORIZON),
                     "--seed", "3", "--out", str(out), "--video", "--video-size", "64")
    assert result.returncode == 0, result.stderr[-4000:]
    observations: dict[int, list[int]] = {}
    (topic,) = [t for t in bag_messages(out / "bag") if t.endswith("/observation")]
    for _, o in bag_messages(out / "bag")[topic]:
        observations.setdefault(o.episode, []).append(o.step)
    return {"out": out, "observations": observations, "stdout": result.stdout}


def gif_frames(path: Path) -> list[np.ndarray]:
    with Image.open(path) as image:
        assert image.format == "GIF"
        return [np.asarray(frame.convert("RGB")) for frame in ImageSequence.Iterator(image)]


def test_session_video_writes_one_video_per_episode_with_a_frame_per_step(recorded):
    out = recorded["out"]
    rows = list(csv.DictReader((out / "episodes.csv").open()))
    assert len(rows) == 4 and "videos/ (4 gif)" in recorded["stdout"]
    for row in rows:
        # The videos are named by the task manager's episode numbers, as `bag render` names them.
        episode, length = int(row["suite_episode"]), int(row["length"])
        frames = gif_frames(out / "videos" / f"episode_{episode:03}.gif")
        assert len(frames) == length + 1 == len(recorded["observations"][episode])
        assert frames[0].shape == (64, 64, 3)
        assert not np.array_equal(frames[0], frames[-1]), "the arm moved"
    assert sorted(p.name for p in (out / "videos").iterdir()) == [
        f"episode_{int(r['suite_episode']):03}.gif" for r in rows]


def test_bag_render_gif_and_mp4_open_in_standard_readers(recorded, tmp_path):
    bag = recorded["out"] / "bag"
    episodes = sorted(e for e, steps in recorded["observations"].items() if max(steps) > 0)
    last = episodes[-1]
    gif = tmp_path / "last.gif"
    result = composuite("bag", "render", str(bag), "--camera", "agentview", "--episode", str(last),
                        "--width", "80", "--height", "60", "--out", str(gif))
    assert f"{HORIZON + 1} frames" in result.stdout
    frames = gif_frames(gif)
    assert len(frames) == len(recorded["observations"][last]) == HORIZON + 1
    assert frames[0].shape == (60, 80, 3)
    assert len(np.unique(frames[0].reshape(-1, 3), axis=0)) > 10, "a scene, not a blank"
    with Image.open(gif) as image:
        assert image.info["duration"] == 50, "20 fps: the control rate"

    # Every episode in one MP4, through the ffmpeg the imageio-ffmpeg wheel ships.
    mp4 = tmp_path / "all.mp4"
    composuite("bag", "render", str(bag), "--out", str(mp4), "--width", "96", "--height", "64",
               "--ffmpeg", imageio_ffmpeg.get_ffmpeg_exe())
    video = np.stack(list(iio.imiter(mp4, plugin="FFMPEG")))
    assert video.shape == (sum(len(recorded["observations"][e]) for e in episodes), 64, 96, 3)
    assert not np.array_equal(video[0], video[HORIZON])

    # The same bag, the same video, byte for byte.
    again = tmp_path / "again.gif"
    composuite("bag", "render", str(bag), "--camera", "agentview", "--episode", str(last),
               "--width", "80", "--height", "60", "--out", str(again))
    assert again.read_bytes() == gif.read_bytes()


@pytest.mark.parametrize("args, says", [
    (["--camera", "front", "--out", "x.gif"], "valid cameras: frontview, agentview, birdview, sideview, eye_in_hand"),
    (["--out", "x.avi"], ".gif or .mp4"),
    (["--episode", "99", "--out", "x.gif"], "--episode 99: not in the bag; episodes of"),
    (["--namespace", "/nope", "--out", "x.gif"], "the bag's environments: /session_"),
    (["--out", "x.mp4", "--ffmpeg", "/no/such/ffmpeg"], "/no/such/ffmpeg: no such file"),
])
def test_bad_render_arguments_say_what_is_valid(recorded, tmp_path, args, says):
    args = [a if not a.startswith("x.") else str(tmp_path / a) for a in args]
    result = composuite("bag", "render", str(recorded["out"] / "bag"), *args, check=False)
    assert result.returncode != 0 and says in result.stderr, result.stderr


def test_an_existing_video_is_never_overwritten(recorded, tmp_path):
    out = tmp_path / "v.gif"
    out.write_bytes(b"keep")
    result = composuite("bag", "render", str(recorded["out"] / "bag"), "--out", str(out), check=False)
    assert result.returncode != 0 and "exists already" in result.stderr
    assert out.read_bytes() == b"keep"
    missing = composuite("bag", "render", str(tmp_path / "nobag"), "--out", str(tmp_path / "w.gif"), check=False)
    assert missing.returncode != 0 and "nobag" in missing.stderr
