"""The addresses another machine can open the page at: a wildcard host (0.0.0.0, ::) is no address to open."""

from __future__ import annotations

import ipaddress
import socket

#: Hosts that mean "every interface of this machine".
WILDCARD_HOSTS = ("0.0.0.0", "::", "")
#: Documentation-only addresses (RFC 5737, RFC 3849): a UDP socket "connected" to them finds the interface
#: the machine's default route leaves by, without sending anything.
_ROUTE_PROBES = ((socket.AF_INET, "192.0.2.1"), (socket.AF_INET6, "2001:db8::1"))


def _route_addresses() -> list[str]:
    """This machine's addresses on its default routes (IPv4, IPv6), found without sending a packet."""
    found = []
    for family, probe in _ROUTE_PROBES:
        try:
            with socket.socket(family, socket.SOCK_DGRAM) as s:
                s.connect((probe, 9))
                found.append(s.getsockname()[0])
        except OSError:  # no route of that family
            continue
    return found


def _name_addresses() -> list[str]:
    """The addresses this machine's host name resolves to."""
    try:
        infos = socket.getaddrinfo(socket.gethostname(), None, proto=socket.IPPROTO_TCP)
    except OSError:
        return []
    return [info[4][0] for info in infos]


def machine_hosts(host: str) -> list[str]:
    """The hosts a browser on another machine can use for a server listening on ``host``.

    Parameters
    ----------
    host : str
        The address listened on. A wildcard (``0.0.0.0``, ``::``) stands for every interface: it becomes this
        machine's routable addresses (loopback and link-local ones left out; IPv6 ones only when listening on
        ``::``), then its host name; ``127.0.0.1`` alone when it has no other. Any other host is itself.

    Returns
    -------
    list of str
        Hosts, most useful first, without duplicates; never a wildcard.
    """
    if host not in WILDCARD_HOSTS:
        return [host]
    ipv6 = host == "::"
    hosts: list[str] = []
    for address in _route_addresses() + _name_addresses():
        try:
            ip = ipaddress.ip_address(address.split("%")[0])
        except ValueError:
            continue
        if ip.is_loopback or ip.is_link_local or ip.is_unspecified or (ip.version == 6 and not ipv6):
            continue
        if str(ip) not in hosts:
            hosts.append(str(ip))
    name = socket.gethostname()
    if hosts and name and name not in hosts and name != "localhost":
        hosts.append(name)
    return hosts or ["127.0.0.1"]


def page_urls(host: str, port: int, query: str = "") -> list[str]:
    """The page's addresses (``http://HOST:PORT/`` plus ``query``) for a server listening on ``host``.

    Parameters
    ----------
    host : str
        The address listened on (see :func:`machine_hosts`).
    port : int
        The port listened on.
    query : str
        Appended as is (e.g. ``?token=...``), or "".
    """
    return [f"http://{f'[{h}]' if ':' in h else h}:{port}/{query}" for h in machine_hosts(host)]
