"""A serial device whose other end is never read: a pty pair whose master
stays open and unread, as a radio or cable that stopped taking bytes
(flow control held off). Prints "ready", then the device's path; runs
until SIGTERM."""
import os
import time
import tty

from ptys import UntilSignalled

master, slave = os.openpty()
tty.setraw(slave)
tty.setraw(master)
print("ready")
print(os.ttyname(slave), flush=True)
until = UntilSignalled()
while until.running:
    time.sleep(0.05)
