"""The address of a Dask scheduler, checked before any work: its form, then that something
Dask-like answers there within a stated time.

A Dask scheduler speaks first: right after accepting a TCP connection it writes its handshake,
a message whose first 8 bytes are the little-endian byte count of what follows (a few hundred
bytes). ``probe_scheduler`` connects, waits at most ``timeout`` seconds for those 8 bytes and
refuses a server that sends nothing (it would hang Dask's client) or announces an absurd size
(Dask would try to allocate it).
"""
import re
import socket
import struct

from quadcog.errors import SchedulerError

__all__ = ["SCHEDULER_TIMEOUT", "MAX_HANDSHAKE", "SCHEMES", "parse_address", "probe_scheduler"]

SCHEDULER_TIMEOUT = 10.0    # s to connect and to receive the scheduler's handshake
MAX_HANDSHAKE = 1 << 20     # bytes: a Dask handshake is far below this
SCHEMES = ("tcp",)          # tls:// and others need a security context: use a dask Client
_ADDRESS = re.compile(r"^(?:(?P<scheme>[A-Za-z][A-Za-z0-9+.-]*)://)?"
                      r"(?P<host>\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+)?(?::(?P<port>\d*))?$")
_FORM = "tcp://HOST:PORT (or HOST:PORT), PORT a whole number 1-65535"


def parse_address(address: object, where: str = "--scheduler") -> tuple[str, int]:
    """(host, port) of a scheduler address, or a SchedulerError naming it.

    Parameters
    ----------
    address : object
        The address as given: ``"tcp://10.0.0.5:8786"`` or ``"10.0.0.5:8786"``.
    where : str
        Where it came from (``--scheduler``, ``scheduler=``), first in the message.

    Returns
    -------
    (str, int)
        Host name or IP address (without brackets) and TCP port.
    """
    if not isinstance(address, str):
        raise SchedulerError(f"{where}: expected an address {_FORM}, got {address!r} "
                             f"({type(address).__name__})")
    m = _ADDRESS.match(address.strip())
    if m is None:
        raise SchedulerError(f"{where} {address!r}: not an address; expected {_FORM}")
    scheme = (m.group("scheme") or "tcp").lower()
    if scheme not in SCHEMES:
        extra = (" (tls:// needs certificates: connect a distributed.Client yourself)"
                 if scheme in ("tls", "wss") else "")
        raise SchedulerError(f"{where} {address!r}: scheme {scheme}:// is not supported"
                             f"{extra}; expected {_FORM}")
    host, port = m.group("host"), m.group("port")
    if not host:
        raise SchedulerError(f"{where} {address!r}: no host; expected {_FORM}")
    if not port:
        raise SchedulerError(f"{where} {address!r}: no port; expected {_FORM}")
    port = int(port)
    if not 1 <= port <= 65535:
        raise SchedulerError(f"{where} {address!r}: port {port} is out of range; expected "
                             f"{_FORM}")
    return host.strip("[]"), port


def probe_scheduler(address: str, timeout: float = SCHEDULER_TIMEOUT,
                    where: str = "--scheduler") -> str:
    """Check that a Dask scheduler answers at ``address`` within ``timeout`` seconds.

    Parameters
    ----------
    address : str
        As for ``parse_address``.
    timeout : float
        Seconds allowed to connect and, again, to receive the handshake's first bytes.
    where : str
        Where the address came from, first in messages.

    Returns
    -------
    str
        The address in Dask's form, ``tcp://host:port``.

    Raises
    ------
    SchedulerError
        Wrong form, no connection, no handshake within ``timeout``, or a handshake that is not
        Dask's.
    """
    host, port = parse_address(address, where)
    target = f"tcp://{'[' + host + ']' if ':' in host else host}:{port}"
    try:
        sock = socket.create_connection((host, port), timeout=timeout)
    except (OSError, ValueError) as e:
        raise SchedulerError(f"{where} {address!r}: cannot connect within {timeout:g} s "
                             f"({getattr(e, 'strerror', None) or e})") from None
    with sock:
        sock.settimeout(timeout)
        head = b""
        try:
            while len(head) < 8:
                part = sock.recv(8 - len(head))
                if not part:
                    raise SchedulerError(f"{where} {address!r}: the server closed the "
                                         f"connection without a Dask handshake")
                head += part
        except socket.timeout:
            raise SchedulerError(f"{where} {address!r}: the server accepted the connection "
                                 f"but sent no Dask handshake within {timeout:g} s (is it a "
                                 f"Dask scheduler?)") from None
        except OSError as e:
            raise SchedulerError(f"{where} {address!r}: reading the handshake failed "
                                 f"({e.strerror or e})") from None
    size = struct.unpack("<Q", head)[0]
    if not 0 < size <= MAX_HANDSHAKE:
        raise SchedulerError(f"{where} {address!r}: the server's first message announces "
                             f"{size} bytes (a Dask handshake is below {MAX_HANDSHAKE}): not "
                             f"a Dask scheduler")
    return target
