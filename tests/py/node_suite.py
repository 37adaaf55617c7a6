"""Start and stop the three node binaries (task_manager_node, sim_node, reward_node) of one
environment for the integration tests, and run the in-process reference `env_replay`.

Binaries come from $COMPOSUITE_NODE_DIR (default: the cargo target directory's debug build,
$CARGO_TARGET_DIR/debug or target/debug); `env_replay` from $COMPOSUITE_ENV_REPLAY (default:
<node dir>/examples/env_replay). The test command (scripts/test) sets both.

Only use it inside scripts/netns-isolate (or netns-run): the nodes speak DDS."""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import random
import signal
import socket
import struct
import subprocess
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
NODES = ("task_manager", "sim", "reward")
# Seconds a node gets to exit after SIGINT.
SHUTDOWN_TIMEOUT = 5.0
CLOCK_TICKS = os.sysconf("SC_CLK_TCK")  # units of /proc/PID/stat times
PAGE_SIZE = os.sysconf("SC_PAGE_SIZE")  # units of /proc/PID/statm sizes


def node_dir() -> Path:
    path = os.environ.get("COMPOSUITE_NODE_DIR")
    if not path:
        target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
        path = str(target / "debug")
    return Path(path)


def binary(node: str) -> Path:
    path = node_dir() / f"{node}_node"
    if not path.is_file():
        raise FileNotFoundError(
            f"{path} not found: build with `cargo build -p composuite_ros --bins` or set COMPOSUITE_NODE_DIR")
    return path


def env_replay_path() -> Path:
    path = Path(os.environ.get("COMPOSUITE_ENV_REPLAY") or node_dir() / "examples" / "env_replay")
    if not path.is_file():
        raise FileNotFoundError(
            f"{path} not found: build with `cargo build -p composuite_ros --example env_replay` "
            "or set COMPOSUITE_ENV_REPLAY")
    return path


def cpu_seconds(pid: int) -> float:
    """User + system CPU seconds of process `pid` so far, all its threads (/proc/PID/stat's utime
    and stime). OSError once the process is gone."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLOCK_TICKS


def rss_bytes(pid: int) -> int:
    """Resident memory of process `pid` in bytes (/proc/PID/statm). OSError once it is gone."""
    return int(Path(f"/proc/{pid}/statm").read_text().split()[1]) * PAGE_SIZE


def node_processes(marker: str, kind: str | None = None) -> list[int]:
    """Pids of `composuite node KIND ...` processes (what `composuite launch` starts) whose command
    line contains `marker` (e.g. `__ns:=/env_00`), of one `kind` if given."""
    pids = []
    for proc in Path("/proc").iterdir():
        if not proc.name.isdigit():
            continue
        try:
            args = (proc / "cmdline").read_bytes().split(b"\0")
        except OSError:
            continue
        line = b" ".join(args).decode(errors="replace")
        if len(args) > 2 and args[1] == b"node" and marker in line and kind in (None, args[2].decode()):
            pids.append(int(proc.name))
    return pids


def env_replay_run(episode: dict) -> list[dict]:
    """`env_replay run` on an episode description: one dict per step, step 0 (reset) first."""
    result = subprocess.run([str(env_replay_path()), "run"], input=json.dumps(episode),
                            capture_output=True, text=True, check=False, timeout=120)
    if result.returncode != 0:
        raise RuntimeError(f"env_replay run failed: {result.stderr}")
    return [json.loads(line) for line in result.stdout.splitlines() if line.strip()]


def env_replay_expert(task: str, seed: int) -> dict:
    result = subprocess.run([str(env_replay_path()), "expert", task, str(seed)],
                            capture_output=True, text=True, check=False, timeout=120)
    if result.returncode != 0:
        raise RuntimeError(f"env_replay expert failed: {result.stderr}")
    return json.loads(result.stdout)


def float_bits(values) -> list[str]:
    """The IEEE-754 bits of each float as hex: equal lists mean bit-identical values (NaNs and
    signed zeros included), which `==` on floats does not tell."""
    return [struct.pack("<d", float(v)).hex() for v in values]


def ns_of(stamp) -> int:
    """A builtin_interfaces/Time as integer nanoseconds (exact, unlike float seconds)."""
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def fastdds_peer() -> Path:
    """The Fast DDS agent of tests/interop/fastdds_secure_peer: $COMPOSUITE_FASTDDS_PEER, else
    built once per source version (`make`, Debian's libfastrtps-dev) into the cache
    ($COMPOSUITE_CACHE, default ~/.cache/composuite-ros)."""
    given = os.environ.get("COMPOSUITE_FASTDDS_PEER")
    if given:
        return Path(given)
    source = REPO / "tests" / "interop" / "fastdds_secure_peer"
    digest = hashlib.sha256()
    for name in ("peer.cpp", "Makefile"):
        digest.update((source / name).read_bytes())
    cache = Path(os.environ.get("COMPOSUITE_CACHE", Path.home() / ".cache" / "composuite-ros"))
    out = cache / "fastdds_secure_peer" / digest.hexdigest()[:16]
    peer = out / "fastdds_secure_peer"
    if not peer.is_file():
        out.mkdir(parents=True, exist_ok=True)
        built = subprocess.run(["make", "-C", str(source), f"OUT={out}"],
                               capture_output=True, text=True, timeout=300)
        if built.returncode != 0:
            raise RuntimeError(f"building the Fast DDS peer failed:\n{built.stdout}{built.stderr}")
    return peer


# The largest ROS_DOMAIN_ID a test picks. A domain's DDS ports are 7400 + 250·id + a few
# dozen; above 101 they land in Linux's ephemeral port range (32768–60999), where any process's
# outgoing socket may already hold one, and the participant then cannot bind it ("failed to
# bind to ANY:57151: address in use" on domain 199, once in a CI run). ROS 2 advises 0–101 on
# Linux for the same reason.
MAX_TEST_DOMAIN = 101


def random_domain() -> int:
    """A ROS_DOMAIN_ID for one test module, so modules never see each other's nodes."""
    require_isolation()
    return random.SystemRandom().randint(1, MAX_TEST_DOMAIN)


def other_domain(domain: int) -> int:
    """A domain other than `domain`, also at most [`MAX_TEST_DOMAIN`]."""
    return domain % MAX_TEST_DOMAIN + 1


# Two-host mode (tests/py/test_two_hosts.py): the name of the network namespace the suite's
# processes are started in ("host a" of scripts/netns-pair); this process then runs on host b.
SUITE_NETNS_VAR = "COMPOSUITE_SUITE_NETNS"


def suite_launcher() -> list[str]:
    """The command prefix that starts a suite process on the suite's host: nothing on one host,
    `ip netns exec <host a>` in two-host mode (it execs, so the pid is the node's own)."""
    netns = os.environ.get(SUITE_NETNS_VAR)
    return ["ip", "netns", "exec", netns] if netns else []


def require_isolation() -> None:
    """Fail unless this process sees only the loopback interface (netns-isolate / netns-run), or,
    in two-host mode, loopback and host b's end of the scripts/netns-pair link; and no route
    leads off the machine."""
    names = sorted(name for _, name in socket.if_nameindex())
    allowed = [["lo"], ["lo", "veth-b"]] if os.environ.get(SUITE_NETNS_VAR) else [["lo"]]
    if names not in allowed:
        raise RuntimeError(f"DDS tests must run inside scripts/netns-isolate (interfaces here: {names})")
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.connect(("192.0.2.1", 7400))  # resolves a route, sends nothing
        except OSError:
            return
    raise RuntimeError("DDS tests must not run where a route leads off the machine")


class Launched:
    """`composuite launch` of one environment of `task` in `namespace` (service format
    `service_mapping`: cyclone for the cyclonedds agent, enhanced for rclpy on Fast DDS; `extra`
    launch options after), its output in a file."""

    def __init__(self, log_dir: Path, namespace: str, task: str, *extra: str,
                 service_mapping: str = "cyclone"):
        self.namespace, self.domain = namespace, random_domain()
        envs = int(extra[extra.index("--envs") + 1]) if "--envs" in extra else 1
        base = "" if namespace == "/" else namespace
        # Each environment's namespace, named as `composuite launch` names them.
        self.namespaces = [namespace] if envs == 1 else [f"{base}/env_{i:02}" for i in range(envs)]
        self.log = log_dir / "launch.stderr"
        env = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
        env["ROS_DOMAIN_ID"] = str(self.domain)
        with open(self.log, "wb") as stderr:
            self.process = subprocess.Popen(
                [*suite_launcher(), str(node_dir() / "composuite"), "launch",
                 "--task", task, "--namespace", namespace, "--service-mapping", service_mapping,
                 "--log-level", "info", *extra],
                env=env, stdin=subprocess.DEVNULL, stdout=stderr, stderr=stderr)

    def text(self) -> str:
        return self.log.read_text(errors="replace")

    def kill_node(self, kind: str) -> int:
        (pid,) = node_processes(f"__ns:={self.namespace}", kind)
        os.kill(pid, signal.SIGKILL)
        return pid

    def wait_for_log(self, text: str, timeout: float = 20.0) -> None:
        deadline = time.monotonic() + timeout
        while text not in self.text():
            assert self.process.poll() is None, f"launch exited:\n{self.text()[-4000:]}"
            assert time.monotonic() < deadline, f"launch never said {text!r}:\n{self.text()[-4000:]}"
            time.sleep(0.05)

    def wait_until_up(self, timeout: float = 20.0) -> None:
        """Until every node of every environment said it is up: an agent created before that
        announces itself to nobody and waits for the nodes' next periodic discovery
        announcement."""
        for namespace in self.namespaces:
            prefix = "" if namespace == "/" else namespace
            for node in NODES:
                self.wait_for_log(f"{prefix}/{node} up", timeout)

    def stop(self) -> None:
        self.process.send_signal(signal.SIGINT)
        try:
            code = self.process.wait(timeout=15)
        except subprocess.TimeoutExpired:
            self.process.kill()
            code = self.process.wait()
        assert code == 0, f"launch exited {code}:\n{self.text()[-4000:]}"
        assert node_processes(f"__ns:={self.namespace}") == [], "nodes left running"


@contextlib.contextmanager
def launch_running(log_dir: Path, namespace: str, task: str, *extra: str, service_mapping: str = "cyclone"):
    """A `Launched` whose nodes are all up, with ROS_DOMAIN_ID set to its domain for the `with`
    body (rclpy agents and subprocesses read it); stopped, and the variable restored, after."""
    suite = Launched(log_dir, namespace, task, *extra, service_mapping=service_mapping)
    previous = os.environ.get("ROS_DOMAIN_ID")
    os.environ["ROS_DOMAIN_ID"] = str(suite.domain)
    try:
        suite.wait_until_up()
        yield suite
    finally:
        suite.stop()
        if previous is None:
            os.environ.pop("ROS_DOMAIN_ID", None)
        else:
            os.environ["ROS_DOMAIN_ID"] = previous


class Suite:
    """The nodes of one environment in `namespace` (all three, or `nodes`), each with its stderr
    in a file.

        suite = Suite(tmp_dir, "/t1", domain_id, task_manager={"service_mapping": "cyclone"})
        ...
        suite.stop()   # SIGINT, then asserts every node exited 0 within SHUTDOWN_TIMEOUT
    """

    def __init__(self, log_dir: Path, namespace: str, domain_id: int,
                 nodes: tuple[str, ...] = NODES, **params: dict[str, object]):
        unknown = (set(params) | set(nodes)) - set(NODES)
        if unknown:
            raise ValueError(f"unknown node(s) {sorted(unknown)}; nodes: {NODES}")
        self.nodes = nodes
        self.namespace, self.domain_id = namespace, domain_id
        self.log_dir = Path(log_dir)
        self.log_dir.mkdir(parents=True, exist_ok=True)
        env = {k: v for k, v in os.environ.items()
               if not k.startswith("ROS_") and k not in ("RMW_IMPLEMENTATION",)}
        env["ROS_DOMAIN_ID"] = str(domain_id)
        self.processes: dict[str, subprocess.Popen] = {}
        self.stderr_paths: dict[str, Path] = {}
        try:
            for node in nodes:
                args = [*suite_launcher(), str(binary(node)), "--ros-args", "-r", f"__ns:={namespace}"]
                for name, value in params.get(node, {}).items():
                    if isinstance(value, bool):
                        value = "true" if value else "false"
                    args += ["-p", f"{name}:={value}"]
                path = self.log_dir / f"{namespace.strip('/').replace('/', '_')}_{node}.stderr"
                self.stderr_paths[node] = path
                with open(path, "wb") as stderr:
                    self.processes[node] = subprocess.Popen(
                        args, stdin=subprocess.DEVNULL, stdout=stderr, stderr=stderr, env=env)
        except BaseException:
            self.kill()
            raise

    def wait_until_up(self, timeout: float = 10.0) -> None:
        """Until every node has said it is up (its DDS participant and endpoints exist). An agent
        made before that announces itself to nobody and is found only at the next periodic
        announcement, seconds later."""
        for node in self.nodes:
            self.wait_for_log(node, f"{self.namespace}/{node} up", timeout)

    def stderr(self, node: str) -> str:
        return self.stderr_paths[node].read_text(errors="replace")

    def all_stderr(self) -> str:
        return "\n".join(f"---- {node} (exit {self.processes[node].poll()}) ----\n{self.stderr(node)}"
                         for node in self.processes)

    def assert_running(self) -> None:
        dead = {n: p.poll() for n, p in self.processes.items() if p.poll() is not None}
        assert not dead, f"node(s) exited: {dead}\n{self.all_stderr()}"

    def wait_for_log(self, node: str, text: str, timeout: float = 5.0, since: int = 0) -> str:
        """The node's stderr from character `since` on, once that part contains `text` (lines
        are written as they are logged)."""
        deadline = time.monotonic() + timeout
        while True:
            log = self.stderr(node)[since:]
            if text in log:
                return log
            if time.monotonic() >= deadline:
                raise AssertionError(f"{node}'s stderr never said {text!r} within {timeout} s:\n{log}")
            time.sleep(0.02)

    def stop(self) -> dict[str, int | None]:
        """SIGINT to every node; the exit status of each (None = still running after the
        timeout, then killed)."""
        for process in self.processes.values():
            if process.poll() is None:
                process.send_signal(signal.SIGINT)
        deadline = time.monotonic() + SHUTDOWN_TIMEOUT
        codes: dict[str, int | None] = {}
        for node, process in self.processes.items():
            try:
                codes[node] = process.wait(timeout=max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                codes[node] = None
        self.kill()
        return codes

    def stop_and_check(self) -> None:
        codes = self.stop()
        bad = {n: c for n, c in codes.items() if c != 0}
        assert not bad, (f"unclean shutdown after SIGINT (None = still running after "
                         f"{SHUTDOWN_TIMEOUT} s): {bad}\n{self.all_stderr()}")

    def kill(self) -> None:
        for process in self.processes.values():
            if process.poll() is None:
                process.kill()
                process.wait()


@contextlib.contextmanager
def running(log_dir: Path, namespace: str, domain_id: int, nodes: tuple[str, ...] = NODES, **params):
    """A Suite (all nodes, or `nodes`) that is up for the `with` body, then stopped; its nodes
    must exit cleanly."""
    suite = Suite(log_dir, namespace, domain_id, nodes, **params)
    try:
        suite.wait_until_up()
    except BaseException:
        suite.kill()
        raise
    yield suite
    suite.stop_and_check()
