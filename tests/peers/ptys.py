"""What the peers that play a cable or a radio between two pseudo-terminals
share: the pair of raw terminals, and running until SIGTERM or SIGINT."""
import os
import select
import signal
import time
import tty


def open_raw_pair():
    """Two pseudo-terminals, raw and without echo: [(master_fd, slave_path)]
    for each end. A pty is a line-editing terminal by default, which would
    echo our frames back and mangle bytes like 0x0D and 0x03. The slave
    ends stay open, so nobody's closing them hangs the other side up."""
    ends = []
    for _ in range(2):
        master, slave = os.openpty()
        tty.setraw(slave)
        tty.setraw(master)
        ends.append((master, os.ttyname(slave)))
    return ends


class UntilSignalled:
    """`.running` is True until SIGTERM or SIGINT arrives."""

    def __init__(self):
        self.running = True
        signal.signal(signal.SIGTERM, self.stop)
        signal.signal(signal.SIGINT, self.stop)

    def stop(self, *_):
        self.running = False


def read_ready(fds, timeout):
    """[(fd, bytes)] for each of `fds` with something to read within
    `timeout` seconds. A master whose slave nobody has opened yet reads as
    an error: nothing to carry, so it is left out after a short pause."""
    try:
        ready, _, _ = select.select(fds, [], [], timeout)
    except InterruptedError:
        return []
    out = []
    for fd in ready:
        try:
            out.append((fd, os.read(fd, 4096)))
        except OSError:
            time.sleep(0.01)
    return out
