"""One PX4 SITL process: a free instance, a private working folder, and a sure end.

PX4 instance ``i`` connects to the simulator on TCP 127.0.0.1:4560 + i, binds the UDP ports
18570 + i (ground station link), 14580 + i (API link, which sends to 14540 + i), 14280 + i and
13030 + i, and holds the lock file /tmp/px4_lock-i (a second PX4 of the same instance refuses
to start). ``free_instance`` takes the first instance all of whose ports and lock are free
and binds its simulator port at once (so no other process takes it in between).

``Px4Process`` runs ``px4 -d -i <i> -w <working folder> <build>/etc`` with the start-up
environment (``PX4_SYS_AUTOSTART``, ``PX4_SIM_MODEL``, the airframe's ``PX4_PARAM_*``), its
console output in ``<working folder>/px4.log``, in a session of its own, and with
``PR_SET_PDEATHSIG`` (``quadcog.interrupts.die_with_parent``) so that it dies with quadcog even
on SIGKILL. ``px4 -d`` ignores SIGTERM: ``stop`` sends SIGKILL to its process group and waits.
"""
import contextlib
import fcntl
import os
from pathlib import Path
import signal
import socket
import subprocess

from quadcog.errors import Px4Error
from quadcog.interrupts import die_with_parent

__all__ = ["SIM_PORT", "MAX_INSTANCES", "px4_ports", "instance_free", "free_instance",
           "Px4Process"]

SIM_PORT = 4560                 # + instance: the simulator's TCP port, which PX4 connects to
MAX_INSTANCES = 10              # PX4's port plan holds for instances 0..9


def px4_ports(instance: int) -> tuple[int, ...]:
    """The UDP ports PX4 instance ``instance`` binds (px4-rc.mavlink) and the mission link's.

    Parameters
    ----------
    instance : int
        0 .. MAX_INSTANCES - 1.

    Returns
    -------
    tuple of int
        18570 + i, 14580 + i, 14280 + i, 13030 + i, 14540 + i.
    """
    return tuple(base + instance for base in (18570, 14580, 14280, 13030, 14540))


def _udp_free(port: int) -> bool:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        try:
            s.bind(("127.0.0.1", port))
        except OSError:
            return False
    return True


def _lock_free(instance: int) -> bool:
    path = f"/tmp/px4_lock-{instance}"
    try:
        fd = os.open(path, os.O_RDWR)
    except FileNotFoundError:
        return True
    except OSError:
        return False
    try:
        fcntl.lockf(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        return False
    else:
        fcntl.lockf(fd, fcntl.LOCK_UN)
        return True
    finally:
        os.close(fd)


def instance_free(instance: int) -> bool:
    """Whether PX4 instance ``instance``'s UDP ports and lock file are free.

    Parameters
    ----------
    instance : int
        The instance.

    Returns
    -------
    bool
        True when a PX4 of that instance could start (its simulator port is checked by
        binding it: ``free_instance``).
    """
    return _lock_free(instance) and all(_udp_free(p) for p in px4_ports(instance))


def free_instance(first: int = 0) -> tuple[int, socket.socket]:
    """The first free PX4 instance and its simulator port, bound and listening.

    Parameters
    ----------
    first : int
        The instance to try first.

    Returns
    -------
    instance : int
        The instance.
    server : socket.socket
        Listening on 127.0.0.1:SIM_PORT + instance.

    Raises
    ------
    quadcog.Px4Error
        When every instance's ports are taken (naming them).
    """
    taken = []
    for i in range(first, MAX_INSTANCES):
        if not instance_free(i):
            taken.append(f"{i} (UDP {'/'.join(map(str, px4_ports(i)))} or /tmp/px4_lock-{i})")
            continue
        server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        # a previous run's closed connection may linger in TIME_WAIT on the port
        server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            server.bind(("127.0.0.1", SIM_PORT + i))
            server.listen(1)
        except OSError:
            server.close()
            taken.append(f"{i} (TCP {SIM_PORT + i})")
            continue
        return i, server
    raise Px4Error(f"no free PX4 instance: the ports of instances {first}..{MAX_INSTANCES - 1} "
                   f"are taken: {'; '.join(taken)}; stop the other PX4 or simulators")


class Px4Process:
    """A running ``px4 -d`` (see the module docstring); a context manager that stops it.

    Parameters
    ----------
    binary : pathlib.Path
        The ``px4`` executable.
    etc : pathlib.Path
        The build's ``etc`` folder.
    instance : int
        Its instance.
    workdir : pathlib.Path
        Its private working folder (parameters, logs), created.
    env : dict of str to str
        Start-up variables added to the environment.
    """

    def __init__(self, binary: Path, etc: Path, instance: int, workdir: Path,
                 env: dict[str, str]) -> None:
        self.workdir = Path(workdir)
        self.workdir.mkdir(parents=True, exist_ok=True)
        self.log = self.workdir / "px4.log"
        self.instance = instance
        full = {k: v for k, v in os.environ.items() if not k.startswith("PX4_")}
        full.update(env)
        with open(self.log, "wb") as fh:
            try:
                self.proc = subprocess.Popen(
                    [str(binary), "-d", "-i", str(instance), "-w", str(self.workdir), str(etc)],
                    cwd=self.workdir, env=full, stdin=subprocess.DEVNULL, stdout=fh,
                    stderr=subprocess.STDOUT, start_new_session=True, preexec_fn=die_with_parent)
            except OSError as e:
                raise Px4Error(f"cannot start {binary}: {e.strerror}") from None

    def alive(self) -> bool:
        """Whether the process still runs.

        Returns
        -------
        bool
            True while it runs.
        """
        return self.proc.poll() is None

    def describe_exit(self) -> str:
        """How it ended, for messages.

        Returns
        -------
        str
            "exit code 1", "killed by SIGSEGV" or "still running".
        """
        code = self.proc.poll()
        if code is None:
            return "still running"
        if code < 0:
            return f"killed by {signal.Signals(-code).name}"
        return f"exit code {code}"

    def last_lines(self, n: int = 3) -> str:
        """The last lines of its console output.

        Parameters
        ----------
        n : int
            How many.

        Returns
        -------
        str
            The last ``n`` non-empty lines of px4.log joined by " | " ("" when unreadable).
        """
        with contextlib.suppress(OSError):
            lines = [ln.strip() for ln in self.log.read_text(errors="replace").splitlines()
                     if ln.strip()]
            return " | ".join(lines[-n:])
        return ""

    def stop(self) -> None:
        """SIGKILL to its process group, wait for it, and remove the lock file and server
        socket a killed PX4 leaves in /tmp (a clean shutdown would remove them)."""
        if self.proc.poll() is None:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(self.proc.pid, signal.SIGKILL)
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.proc.wait(timeout=10)
        if self.proc.poll() is not None:
            for leftover in (f"/tmp/px4_lock-{self.instance}", f"/tmp/px4-sock-{self.instance}"):
                with contextlib.suppress(OSError):
                    os.unlink(leftover)

    def __enter__(self) -> "Px4Process":
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()
