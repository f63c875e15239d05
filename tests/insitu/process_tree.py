"""Process trees for the robustness and live tests, read from /proc (no tools needed).

listening(pid) -> set of (pid, command, protocol, port) for every TCP socket in LISTEN state and
every bound, unconnected UDP socket that the process tree of `pid` holds: spate and every child it
starts (the in-situ helper, OpenMPI's daemons) must open no listening socket (docs/live.md,
Security).
environment(pid) -> the environment variables a process started with (a dict; {} once it is gone).
kill_groups(processes) kills the process groups of the tests' children that still run (each is
started with start_new_session=True, so that its own children go too).
"""
import os
import signal


def kill_groups(processes):
    for p in processes:
        if p.poll() is None:
            try:
                os.killpg(p.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass


def descendants(pid):
    """pid and every process below it (a snapshot; processes come and go)."""
    children = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                stat = f.read()
        except OSError:
            continue
        # The command is in parentheses and may hold spaces: the fields after the last ')' are fixed.
        fields = stat[stat.rfind(")") + 2:].split()
        children.setdefault(int(fields[1]), []).append(int(entry))
    tree, todo = [], [pid]
    while todo:
        p = todo.pop()
        tree.append(p)
        todo.extend(children.get(p, []))
    return tree


def command(pid):
    try:
        with open(f"/proc/{pid}/comm") as f:
            return f.read().strip()
    except OSError:
        return "?"


def environment(pid):
    try:
        with open(f"/proc/{pid}/environ", "rb") as f:
            pairs = f.read().split(b"\0")
    except OSError:
        return {}
    return dict(p.decode(errors="replace").split("=", 1) for p in pairs if b"=" in p)


def socket_inodes(pid):
    inodes = set()
    try:
        for fd in os.listdir(f"/proc/{pid}/fd"):
            try:
                link = os.readlink(f"/proc/{pid}/fd/{fd}")
            except OSError:
                continue
            if link.startswith("socket:["):
                inodes.add(link[8:-1])
    except OSError:
        pass
    return inodes


def _table(name):
    try:
        with open(f"/proc/net/{name}") as f:
            return [row.split() for row in f.read().splitlines()[1:]]
    except OSError:
        return []


def listening(pid):
    found = set()
    tables = {name: _table(name) for name in ("tcp", "tcp6", "udp", "udp6")}
    for p in descendants(pid):
        inodes = socket_inodes(p)
        if not inodes:
            continue
        for name, rows in tables.items():
            for f in rows:
                if f[9] not in inodes:
                    continue
                state = f[3]
                remote_port = int(f[2].rsplit(":", 1)[1], 16)
                # TCP 0A is LISTEN; a UDP socket with no peer (remote port 0) receives from anyone.
                if (name.startswith("tcp") and state == "0A") or (name.startswith("udp") and remote_port == 0):
                    found.add((p, command(p), name, int(f[1].rsplit(":", 1)[1], 16)))
    return found
