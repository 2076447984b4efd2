"""A real, single-node SLURM cluster on this machine, for testing the SLURM profile.

Debian's slurm-wlm (slurmctld, slurmd, client commands) and munge, started by hand as root (no
systemd), everything they write kept in one temporary directory but for two fixed places:
munged's socket in /run/munge and slurmd's link /run/slurm/conf (both directories removed again
by stop() when this cluster created them; a file lock keeps to one such cluster per machine):

    cluster = LocalSlurm()
    cluster.start()          # munged, slurmctld, slurmd; returns once `sinfo` shows the node idle
    ...  env=cluster.env()   # SLURM_CONF for sbatch/squeue/sinfo run by the caller
    cluster.stop()           # cancels its jobs, kills exactly the pids it started, removes the dir

or from a shell: `python tests/slurm_localhost.py start` (prints the directory and the
`export SLURM_CONF=...` line) and `python tests/slurm_localhost.py stop DIR`.

Choices that a job run through snakemake-executor-plugin-slurm needs:
- configless mode (SlurmctldParameters=enable_configless, slurmd --conf-server): the plugin runs
  each job through a nested `srun` that strips every SLURM_* variable, SLURM_CONF included, so
  the srun inside a job finds the configuration only through the copy slurmd caches under
  /run/slurm/conf;
- DefMemPerCPU (memory is a consumable resource): otherwise a job gets the whole node's memory
  and jobs run one at a time;
- no slurmdbd, so no sacct: the profile queries squeue, which sees a finished job for MinJobAge
  seconds (300 here; the plugin wants >= 3 x its first status-check delay).

The node is this host with the CPUs and memory `slurmd -C` detects; every address in the
configuration is 127.0.0.1 (SLURM has no bind-address setting: slurmctld and slurmd listen on
0.0.0.0 at two free ports chosen here, munge-authenticated with a key made for this cluster, and
nothing is ever sent off the machine).
"""
from __future__ import annotations

import argparse
import fcntl
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

PACKAGES = ("slurm-wlm", "slurmctld", "slurmd", "slurm-client", "munge")
COMMANDS = ("munged", "slurmctld", "slurmd", "sbatch", "squeue", "sinfo", "srun", "scontrol", "scancel")
DAEMONS = ("munged", "slurmctld", "slurmd")  # started in this order, stopped in the reverse one
SYSTEM_CONF = Path("/etc/slurm/slurm.conf")
RUN_DIR = Path("/run/slurm")  # where slurmd links the configuration it fetched (configless mode)
# slurmd in configless mode authenticates its configuration request before it has any
# configuration, so through munge's default socket: munged listens there (a munged already
# serving it, e.g. a real installation's, is used as it is and left alone)
MUNGE_SOCKET = Path("/run/munge/munge.socket.2")
STATE_FILE = "spreadmap-slurm.json"
# /run/munge and /run/slurm are per machine: one cluster at a time (a second one waits for this lock)
LOCK_FILE = Path(tempfile.gettempdir()) / "spreadmap-slurm.lock"


class SlurmUnavailable(RuntimeError):
    """This machine cannot run the localhost cluster (the message says why): not root, no apt,
    the packages cannot be installed, or a SLURM configuration of its own is in the way."""


class SlurmStartError(RuntimeError):
    """The packages are there but the cluster did not come up (the daemons' logs are quoted)."""


def missing_commands() -> list[str]:
    sbin = os.pathsep.join([os.environ.get("PATH", ""), "/usr/sbin", "/sbin"])
    return [c for c in COMMANDS if shutil.which(c, path=sbin) is None]


def ensure_packages(quiet: bool = True) -> float:
    """Install Debian's SLURM and munge packages if a command is missing; returns the seconds spent.
    Raises SlurmUnavailable when that cannot be done (not root, apt fails)."""
    missing = missing_commands()
    if not missing:
        return 0.0
    if os.geteuid() != 0:
        raise SlurmUnavailable(f"not root: cannot apt-get install {' '.join(PACKAGES)} (missing: {' '.join(missing)})")
    if shutil.which("apt-get") is None:
        raise SlurmUnavailable("no apt-get on this machine: cannot install Debian's slurm-wlm and munge")
    start = time.monotonic()
    env = {**os.environ, "DEBIAN_FRONTEND": "noninteractive"}
    for cmd in (["apt-get", "update", "-qq"],
                ["apt-get", "install", "-y", "-qq", "--no-install-recommends", *PACKAGES]):
        try:
            proc = subprocess.run(cmd, env=env, capture_output=True, text=True, stdin=subprocess.DEVNULL, timeout=600)
        except subprocess.TimeoutExpired:
            raise SlurmUnavailable(f"`{' '.join(cmd)}` did not finish in 600 s") from None
        if proc.returncode != 0:
            tail = "\n".join((proc.stdout + proc.stderr).strip().splitlines()[-5:])
            raise SlurmUnavailable(f"`{' '.join(cmd)}` failed (exit {proc.returncode}): {tail}")
    still = missing_commands()
    if still:
        raise SlurmStartError(f"installed {' '.join(PACKAGES)} but still missing: {' '.join(still)}")
    return time.monotonic() - start


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def detected_node() -> dict[str, str]:
    """This host as slurmd sees it (`slurmd -C`): CPUs, Boards, SocketsPerBoard, ..., RealMemory."""
    out = subprocess.run([_sbin("slurmd"), "-C"], capture_output=True, text=True, check=True, timeout=30).stdout
    line = next(ln for ln in out.splitlines() if ln.startswith("NodeName="))
    fields = dict(item.split("=", 1) for item in line.split())
    fields.pop("NodeName", None)
    fields.pop("UpTime", None)
    return fields


def _sbin(name: str) -> str:
    return shutil.which(name, path=os.pathsep.join([os.environ.get("PATH", ""), "/usr/sbin", "/sbin"])) or name


def munge_answers() -> bool:
    """A munged serves the default socket (connect() succeeds)."""
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
        try:
            s.connect(str(MUNGE_SOCKET))
            return True
        except OSError:
            return False


def _pid_alive(pid: int, name: str) -> bool:
    """pid is a live process named `name` (not a zombie, not a recycled pid of something else).
    The name is the kernel's comm: Debian's slurmd and slurmctld are alternatives of *-wlm."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    comm = stat[stat.index("(") + 1:stat.rindex(")")]
    state = stat[stat.rindex(")") + 1:].split()[0]
    return state != "Z" and comm == name


class LocalSlurm:
    """One single-node SLURM cluster; all state in `self.dir` (a new temporary directory)."""

    def __init__(self, directory: Path | str | None = None, partition: str = "debug", def_mem_per_cpu: int = 1000,
                 min_job_age: int = 300):
        self.dir = Path(directory) if directory else Path(tempfile.mkdtemp(prefix="spreadmap-slurm-"))
        self.partition = partition
        self.def_mem_per_cpu = def_mem_per_cpu
        self.min_job_age = min_job_age
        self.pids: dict[str, int] = {}
        self.node = socket.gethostname().split(".")[0]
        self.run_dir_created = False  # /run/slurm did not exist before: remove it at stop
        self.munge_dir_created = False  # same for /run/munge
        self._procs: dict[str, subprocess.Popen] = {}
        self.shared_munge = False  # a munged was already serving MUNGE_SOCKET
        self._lock = None

    # -- configuration -----------------------------------------------------------------------
    @property
    def conf(self) -> Path:
        return self.dir / "slurm.conf"

    def env(self, base: dict | None = None) -> dict:
        """The environment for client commands (sbatch, squeue, sinfo, snakemake) of this cluster."""
        env = {k: v for k, v in (os.environ if base is None else base).items() if not k.startswith("SLURM_")}
        env["SLURM_CONF"] = str(self.conf)
        return env

    def write_config(self) -> None:
        for sub in ("munge", "state", "spool", "log"):
            (self.dir / sub).mkdir(parents=True, exist_ok=True)
        os.chmod(self.dir, 0o700)
        os.chmod(self.dir / "munge", 0o700)
        key = self.dir / "munge" / "munge.key"
        key.write_bytes(os.urandom(1024))
        os.chmod(key, 0o400)
        self.ctld_port, self.slurmd_port = free_port(), free_port()
        while self.slurmd_port == self.ctld_port:
            self.slurmd_port = free_port()
        node = " ".join(f"{k}={v}" for k, v in detected_node().items())
        d = self.dir
        # ProctrackType pgid: a job's processes are signalled by their process group, as a site's
        # cgroup tracking reaches them all. With linuxproc (by parent links) a requeued job's
        # `python -m snakemake` outlived its job once in three runs (2026-12-07). The likely path, not
        # traced: the batch shell died on the SIGTERM, the snakemake job process (still cleaning up)
        # became init's child, and the SIGKILL that follows walks the tree from slurmstepd, no longer
        # reaching it. A process group survives its leader and the re-parenting. (YADE, in a session of
        # its own, dies with its launcher: spreadmap.case.launcher's pdeathsig.)
        self.conf.write_text(f"""\
# Written by tests/slurm_localhost.py: a throw-away single-node cluster on 127.0.0.1.
ClusterName=spreadmap-test
SlurmctldHost={self.node}(127.0.0.1)
SlurmctldPort={self.ctld_port}
SlurmdPort={self.slurmd_port}
SlurmctldParameters=enable_configless
AuthType=auth/munge
CredType=cred/munge
SlurmUser=root
SlurmdUser=root
StateSaveLocation={d}/state
SlurmdSpoolDir={d}/spool
SlurmctldPidFile={d}/slurmctld.pid
SlurmdPidFile={d}/slurmd.pid
SlurmctldLogFile={d}/log/slurmctld.log
SlurmdLogFile={d}/log/slurmd.log
ProctrackType=proctrack/pgid
TaskPlugin=task/affinity
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SwitchType=switch/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU_Memory
DefMemPerCPU={self.def_mem_per_cpu}
MinJobAge={self.min_job_age}
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
NodeName={self.node} NodeAddr=127.0.0.1 NodeHostname={self.node} {node} State=UNKNOWN
PartitionName={self.partition} Nodes={self.node} Default=YES MaxTime=INFINITE State=UP
""")

    # -- start / stop ------------------------------------------------------------------------
    def _spawn(self, name: str, cmd: list[str]) -> None:
        log = open(self.dir / "log" / f"{name}.out", "ab")
        proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
                                env=self.env(), cwd=self.dir, start_new_session=True)
        log.close()
        self._procs[name] = proc
        self.pids[name] = proc.pid
        (self.dir / f"spreadmap-{name}.pid").write_text(f"{proc.pid}\n")
        self._save_state()

    def _save_state(self) -> None:
        (self.dir / STATE_FILE).write_text(json.dumps(
            {"pids": self.pids, "node": self.node, "run_dir_created": self.run_dir_created,
             "munge_dir_created": self.munge_dir_created}, indent=1))

    def _wait(self, what: str, check, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for name, proc in self._procs.items():
                if proc.poll() is not None:
                    raise SlurmStartError(f"{name} exited with code {proc.returncode} while waiting for {what}:\n"
                                           + self.log_tail(name))
            if check():
                return
            time.sleep(0.2)
        raise SlurmStartError(f"timed out after {timeout:.0f} s waiting for {what}:\n" + self.log_tail())

    def log_tail(self, name: str | None = None, lines: int = 15) -> str:
        names = [name] if name else list(DAEMONS)
        out = []
        for n in names:
            for path in (self.dir / "log" / f"{n}.out", self.dir / "log" / f"{n}.log"):
                if path.exists():
                    text = path.read_text(errors="replace").strip().splitlines()[-lines:]
                    out.append(f"--- {path.name}\n" + "\n".join(text))
        return "\n".join(out)

    def client(self, *args: str, timeout: float = 30, check: bool = True) -> subprocess.CompletedProcess:
        return subprocess.run(list(args), env=self.env(), capture_output=True, text=True, timeout=timeout, check=check,
                              stdin=subprocess.DEVNULL)

    def node_state(self) -> str:
        proc = self.client("sinfo", "-h", "-N", "-n", self.node, "-o", "%T", check=False, timeout=10)
        return proc.stdout.strip() if proc.returncode == 0 else ""

    def start(self, timeout: float = 60) -> "LocalSlurm":
        if os.geteuid() != 0:
            raise SlurmUnavailable("not root: munged, slurmctld and slurmd are started by hand as root")
        if SYSTEM_CONF.exists():
            raise SlurmUnavailable(f"{SYSTEM_CONF} exists: this machine has a SLURM configuration of its own, which "
                                   "the nested srun of each job would read instead of this test cluster's")
        missing = missing_commands()
        if missing:
            raise SlurmUnavailable(f"missing SLURM commands: {' '.join(missing)} (see ensure_packages)")
        try:
            self._acquire_lock(timeout=300)
            self.write_config()
            if not RUN_DIR.exists():
                self.run_dir_created = True  # slurmd creates it; stop() removes it again
            if munge_answers():
                self.shared_munge = True
            else:
                if not MUNGE_SOCKET.parent.exists():
                    MUNGE_SOCKET.parent.mkdir(mode=0o755, parents=True)
                    self.munge_dir_created = True
                self._spawn("munged", [_sbin("munged"), "--foreground", "--force",
                                       f"--key-file={self.dir}/munge/munge.key", f"--socket={MUNGE_SOCKET}",
                                       f"--pid-file={self.dir}/munge/munged.pid",
                                       f"--log-file={self.dir}/log/munged.log",
                                       f"--seed-file={self.dir}/munge/munge.seed"])
                self._wait("munged to answer", munge_answers, timeout)
            self._spawn("slurmctld", [_sbin("slurmctld"), "-D", "-i", "-f", str(self.conf)])
            self._wait("slurmctld to answer", lambda: self.client("scontrol", "ping", check=False, timeout=10)
                       .stdout.find("is UP") >= 0, timeout)
            self._spawn("slurmd", [_sbin("slurmd"), "-D", "-N", self.node,
                                   "--conf-server", f"127.0.0.1:{self.ctld_port}"])
            self._wait(f"node {self.node} idle in sinfo", lambda: self.node_state() == "idle", timeout)
        except BaseException:
            self.stop()
            raise
        return self

    def _acquire_lock(self, timeout: float) -> None:
        self._lock = open(LOCK_FILE, "a")
        deadline = time.monotonic() + timeout
        while True:
            try:
                fcntl.flock(self._lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
                return
            except BlockingIOError:
                if time.monotonic() > deadline:
                    raise SlurmStartError(f"another localhost SLURM held {LOCK_FILE} for {timeout:.0f} s") from None
                time.sleep(1)

    def stop(self, remove: bool = True) -> list[str]:
        """Cancel this cluster's jobs, kill the daemons this object started (by pid, nothing else),
        remove the temporary directory. Returns what it did, for the caller's log."""
        done = []
        if self.pids.get("slurmctld") and _pid_alive(self.pids["slurmctld"], "slurmctld"):
            # every job of this private cluster was submitted by its user: cancel them all, so that
            # no slurmstepd or job process outlives the daemons
            try:
                self.client("scancel", "--full", f"--partition={self.partition}", check=False, timeout=15)
                deadline = time.monotonic() + 15
                while time.monotonic() < deadline:
                    q = self.client("squeue", "-h", "-t", "PD,R,CG,CF,S", "-o", "%i", check=False, timeout=10)
                    if q.returncode != 0 or not q.stdout.strip():
                        break
                    time.sleep(0.5)
            except subprocess.SubprocessError as error:
                done.append(f"could not cancel the jobs: {error}")
        for name in reversed(DAEMONS):
            pid = self.pids.get(name)
            if not pid:
                continue
            proc = self._procs.get(name)
            if _pid_alive(pid, name):
                for sig in (signal.SIGTERM, signal.SIGKILL):
                    try:
                        os.kill(pid, sig)
                    except ProcessLookupError:
                        break
                    deadline = time.monotonic() + 10
                    while time.monotonic() < deadline and _pid_alive(pid, name):
                        if proc is not None:
                            proc.poll()
                        time.sleep(0.1)
                    if not _pid_alive(pid, name):
                        break
                done.append(f"stopped {name} (pid {pid})")
            if proc is not None:
                try:
                    proc.wait(timeout=5)
                except subprocess.TimeoutExpired:
                    pass
        self.pids.clear()
        self._procs.clear()
        if self.munge_dir_created and MUNGE_SOCKET.parent.exists():
            shutil.rmtree(MUNGE_SOCKET.parent, ignore_errors=True)
            done.append(f"removed {MUNGE_SOCKET.parent} (created for this cluster's munged)")
        if self.run_dir_created and RUN_DIR.exists():
            shutil.rmtree(RUN_DIR, ignore_errors=True)
            done.append(f"removed {RUN_DIR} (created by this cluster's slurmd)")
        if remove and self.dir.exists():
            shutil.rmtree(self.dir, ignore_errors=True)
            done.append(f"removed {self.dir}")
        if self._lock is not None:
            self._lock.close()  # releases the lock
            self._lock = None
        return done

    @classmethod
    def attach(cls, directory: Path | str) -> "LocalSlurm":
        """The cluster started earlier (by another process) in `directory`, for stop()."""
        directory = Path(directory)
        state = json.loads((directory / STATE_FILE).read_text())
        cluster = cls(directory)
        cluster.pids = {k: int(v) for k, v in state["pids"].items()}
        cluster.run_dir_created = state["run_dir_created"]
        cluster.munge_dir_created = state["munge_dir_created"]
        cluster.node = state["node"]
        return cluster

    def __enter__(self) -> "LocalSlurm":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="action", required=True)
    sub.add_parser("install", help="apt-get install the Debian packages if a command is missing")
    sub.add_parser("start", help="install if needed, start the cluster, print its directory")
    stop = sub.add_parser("stop", help="stop the cluster started in DIR and remove DIR")
    stop.add_argument("dir")
    args = parser.parse_args(argv)
    try:
        if args.action in ("install", "start"):
            spent = ensure_packages()
            if spent:
                print(f"installed {' '.join(PACKAGES)} in {spent:.0f} s", file=sys.stderr)
        if args.action == "start":
            cluster = LocalSlurm().start()
            print(f"started munged, slurmctld, slurmd: pids {cluster.pids}", file=sys.stderr)
            print(f"export SLURM_CONF={cluster.conf}")
            print(f"# stop with: python {sys.argv[0]} stop {cluster.dir}")
        elif args.action == "stop":
            for line in LocalSlurm.attach(args.dir).stop():
                print(line, file=sys.stderr)
    except (SlurmUnavailable, SlurmStartError) as error:
        print(f"slurm_localhost: {error}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
