"""Fills every socket of an LCM multicast port that is not being read.

  python3 lcm_flood.py GROUP PORT COUNT

Sends COUNT datagrams of LCM's small-message format (magic "LC02", sequence
number, channel name, payload) on channel FLOOD, 1200 payload bytes each,
with TTL 0: 30000 of them (about 36 MB) overflow any receive buffer
net.core.rmem_max allows. Run only inside a private network namespace whose
multicast route is on its loopback (tests/integration/lib.sh).
"""
import socket
import struct
import sys
import time

group, port, count = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)
payload = bytes(1200)
for seqno in range(count):
    datagram = struct.pack(">II", 0x4C433032, seqno) + b"FLOOD\0" + payload
    for attempt in range(100):
        try:
            sock.sendto(datagram, (group, port))
            break
        except OSError:  # ENOBUFS: the sender's own buffer, for a moment
            time.sleep(0.001)
print("flood: %d datagrams sent to %s:%d" % (count, group, port))
