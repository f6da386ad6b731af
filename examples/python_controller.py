#!/usr/bin/python3
"""A pidlab controller in Python: the reference for a foreign controller.

It takes pidlab-controller's place in the trio and answers the plant exactly
as pidlab-controller does (controller/src/controller_role.cc,
transport/src/role.cc): every plant output y_k gets u_k = PID(r, y_k), with the
same discrete PID (controller/include/pidlab/controller/pid.h) computed in the
same order of operations, so the loop's IAE is the same bits as with the C++
trio. docs/protocol.md describes the protocol this file follows.

    pidlab launch --roles plant,disturbance &          # the rest of the trio
    PYTHONPATH=<build>/python examples/python_controller.py
    pidlab evaluate --backend lcm --loop sampled --plant oscillator --gains 2,1,1.5

Debian 12 packages no Python binding of LCM (python3-lcm does not exist), so
this file speaks LCM's UDP multicast wire format itself with the socket
module: one datagram per message, "LC02" magic, sequence number, channel name
with a NUL, the encoded message. The messages are encoded and decoded by the
classes lcm-gen --python makes from lcmtypes/*.lcm (the package `pidlab`; the
build puts it in <build>/python, `cmake --install` in
<prefix>/lib/python3/dist-packages).

Not supported: --auth-key (HMAC tags, docs/security.md) and memq:// URLs.
"""

import argparse
import json
import math
import os
import select
import signal
import socket
import struct
import sys
import time

from pidlab.lcmt_control_command import lcmt_control_command
from pidlab.lcmt_episode_config import lcmt_episode_config
from pidlab.lcmt_plant_output import lcmt_plant_output
from pidlab.lcmt_ready import lcmt_ready

DEFAULT_LCM_URL = "udpm://239.255.76.67:7667?ttl=0"  # transport/protocol.h, kDefaultLcmUrl
DEFAULT_CHANNEL_PREFIX = "PIDLAB_"
# transport/transport.h: PLANT_OUTPUT travels on the base port + 1, CONTROL on
# the base port + 2 (the "step lanes"); every other channel on the base port.
PLANT_OUTPUT_LANE = 1
CONTROL_LANE = 2
MAX_EPISODE_STEPS = 50_000_000  # transport/episode_spec.h, kMaxEpisodeSteps
MAX_GAIN = 1e12  # controller/pid.h, kMaxGain

# LCM's UDP multicast framing (lcm_udpm.c of LCM 1.3.1).
LCM_SHORT_MAGIC = 0x4C433032  # "LC02": a whole message in one datagram
LCM_FRAGMENT_MAGIC = 0x4C433033  # "LC03": one fragment of a message too big for one datagram
LCM_MAX_CHANNEL_BYTES = 63
# LCM sends a message of at most this many bytes (channel, NUL and payload)
# as one LC02 datagram. Everything this controller sends or must receive is
# far smaller (a configuration is under 2 kB, a plant output 48 bytes), so
# LC03 fragments (the plant's trajectory chunks, at most) are ignored.
LCM_SHORT_MESSAGE_MAX_SIZE = 65499


def now_utime():
    return int(time.time() * 1e6)


class UdpmUrl:
    """udpm://GROUP[:PORT][?ttl=N&recv_buf_size=N] (LCM's defaults: port 7667, ttl 0)."""

    def __init__(self, url):
        if not url.startswith("udpm://"):
            raise ValueError("LCM URL '%s' is not udpm:// (this controller speaks UDP multicast only)" % url[:120])
        rest = url[len("udpm://"):]
        address, _, query = rest.partition("?")
        group, _, port = address.rpartition(":") if ":" in address else (address, "", "7667")
        if not group or not port.isdigit() or not 1 <= int(port) <= 65535 - CONTROL_LANE:
            raise ValueError("LCM URL '%s': expected udpm://GROUP:PORT with a port at most 65533" % url[:120])
        self.group, self.port = group, int(port)
        self.ttl, self.recv_buf_size = 0, 0
        for item in filter(None, query.split("&")):
            key, _, value = item.partition("=")
            if key == "ttl":
                self.ttl = int(value)
            elif key == "recv_buf_size":
                self.recv_buf_size = int(value)
        socket.inet_aton(self.group)  # raises for a malformed group


class LcmUdpm:
    """Just enough of LCM's udpm transport: receive LC02 datagrams on chosen
    ports of the group, publish LC02 datagrams to a port of the group."""

    def __init__(self, url):
        self.url = url
        self.seqno = 0
        self.send_sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
        self.send_sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, url.ttl)
        self.send_sock.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)
        self.recv_socks = {}  # socket -> port offset (lane)
        self.fragments_ignored = 0
        self.malformed = 0

    def listen(self, lane):
        """Receives what is sent to the group on the base port + lane. Like
        LCM, SO_REUSEADDR lets every process of the host bind the same port,
        and each gets its own copy of every datagram."""
        s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        if self.url.recv_buf_size > 0:
            s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, self.url.recv_buf_size)
        s.bind(("", self.url.port + lane))
        mreq = struct.pack("4s4s", socket.inet_aton(self.url.group), socket.inet_aton("0.0.0.0"))
        s.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, mreq)
        self.recv_socks[s] = lane

    def publish(self, lane, channel, payload):
        name = channel.encode("utf-8")
        if len(name) > LCM_MAX_CHANNEL_BYTES or len(name) + 1 + len(payload) > LCM_SHORT_MESSAGE_MAX_SIZE:
            raise ValueError("message on %s too long for one datagram" % channel)
        header = struct.pack(">II", LCM_SHORT_MAGIC, self.seqno & 0xFFFFFFFF)
        self.seqno += 1
        self.send_sock.sendto(header + name + b"\0" + payload, (self.url.group, self.url.port + lane))

    def receive(self, timeout_s):
        """Yields (lane, channel, payload) of the LC02 datagrams that arrive
        within timeout_s (all that are ready after the first wait)."""
        ready, _, _ = select.select(list(self.recv_socks), [], [], timeout_s)
        for s in ready:
            data = s.recv(65536)
            if len(data) < 8:
                self.malformed += 1
                continue
            magic, _seqno = struct.unpack_from(">II", data, 0)
            if magic == LCM_FRAGMENT_MAGIC:
                self.fragments_ignored += 1
                continue
            end = data.find(b"\0", 8)
            if magic != LCM_SHORT_MAGIC or end < 0 or end - 8 > LCM_MAX_CHANNEL_BYTES:
                self.malformed += 1
                continue
            channel = data[8:end].decode("utf-8", "replace")
            yield self.recv_socks[s], channel, data[end + 1:]


class DiscretePid:
    """controller/include/pidlab/controller/pid.h, DiscretePid<double>::Step,
    operation for operation (Python floats are IEEE doubles, and the C++ is
    built without FMA contraction: the same expressions give the same bits)."""

    OK, SATURATED, INVALID_INPUT = 0, 1, 2

    def __init__(self, kp, ki, kd, dt_s, derivative_filter_s, output_min, output_max, anti_windup,
                 back_calculation_gain, setpoint_weight_b, setpoint_weight_c, integral, setpoint_filter_s=0.0):
        self.kp, self.ki, self.kd = kp, ki, kd
        self.dt = dt_s
        self.tf = derivative_filter_s
        self.output_min, self.output_max = output_min, output_max
        self.anti_windup = anti_windup
        self.back_calculation_gain = back_calculation_gain
        self.b, self.c = setpoint_weight_b, setpoint_weight_c  # the 2-DOF PID's setpoint weights
        self.integral_method = integral
        self.tr = setpoint_filter_s  # the setpoint filter r / (tr s + 1); 0 = none
        self.filtered_r = 0.0
        self.integral = 0.0
        self.derivative = 0.0
        self.prev_error = 0.0
        self.prev_signal = 0.0

    def step(self, r, y):
        """Returns (status, u); u is None for INVALID_INPUT (state untouched)."""
        if not (math.isfinite(r) and math.isfinite(y)):
            return self.INVALID_INPUT, None
        dt = self.dt
        if self.tr > 0.0:  # the setpoint filter's f_k in r's place
            self.filtered_r += dt / (self.tr + dt) * (r - self.filtered_r)
            r = self.filtered_r
        e = r - y
        p = self.kp * (self.b * r - y)
        integral = self.integral
        if self.integral_method == "backward-euler":
            integral += self.ki * dt * e
        elif self.integral_method == "forward-euler":
            integral += self.ki * dt * self.prev_error
        else:  # trapezoidal
            integral += self.ki * (dt * 0.5) * (e + self.prev_error)
        signal_ = self.c * r - y
        tf = self.tf
        d = (tf / (tf + dt)) * self.derivative + self.kd * (signal_ - self.prev_signal) * (1.0 / (tf + dt))
        unsaturated = p + integral + d
        out = unsaturated
        saturated = False
        if out > self.output_max:
            out = self.output_max
            saturated = True
        if out < self.output_min:
            out = self.output_min
            saturated = True
        if saturated:
            if self.anti_windup == "clamping":
                pushes_further = (unsaturated > self.output_max and e > 0.0) or (
                    unsaturated < self.output_min and e < 0.0)
                if pushes_further:
                    integral = self.integral
            elif self.anti_windup == "back-calculation":
                integral += (self.back_calculation_gain * dt) * (out - unsaturated)
        self.integral = integral
        self.derivative = d
        self.prev_error = e
        self.prev_signal = signal_
        return (self.SATURATED if saturated else self.OK), out


def config_error(m):
    """Why a configuration must be ignored, or None. The controller's share of
    transport::ParseEpisodeConfig and EpisodeSpec::IsValid: what it uses."""
    if m.episode_id == 0:
        return "episode id 0"
    for name in ("kp", "ki", "kd"):
        v = getattr(m, name)
        if not (math.isfinite(v) and 0.0 <= v <= MAX_GAIN):
            return "gain %s = %r must be finite, >= 0 and at most 1e12" % (name, v)
    if not math.isfinite(m.reference):
        return "reference %r must be finite" % m.reference
    if not (math.isfinite(m.dt_s) and m.dt_s > 0.0):
        return "dt %r s must be positive and finite" % m.dt_s
    if not 1 <= m.total_steps <= MAX_EPISODE_STEPS:
        return "total steps %d out of [1, 5e7]" % m.total_steps
    if not (math.isfinite(m.derivative_filter_s) and m.derivative_filter_s >= 0.0):
        return "derivative filter %r s must be >= 0 and finite" % m.derivative_filter_s
    if math.isnan(m.output_min) or math.isnan(m.output_max) or not m.output_min < m.output_max:
        return "output limits [%r, %r] must satisfy min < max" % (m.output_min, m.output_max)
    if m.anti_windup not in ("none", "clamping", "back-calculation"):
        return "anti-windup '%s' unknown" % m.anti_windup[:80]
    if m.anti_windup == "back-calculation" and not (
            math.isfinite(m.back_calculation_gain) and m.back_calculation_gain > 0.0):
        return "back-calculation gain %r must be positive" % m.back_calculation_gain
    if m.derivative_on not in ("error", "measurement"):
        return "derivative-on '%s' unknown" % m.derivative_on[:80]
    for name in ("setpoint_weight_b", "setpoint_weight_c"):
        v = getattr(m, name)
        if not (math.isfinite(v) and 0.0 <= v <= 1.0):
            return "setpoint weight %s = %r must be finite and in [0, 1]" % (name[-1], v)
    tr = getattr(m, "setpoint_filter_s", 0.0)  # 0 in the types before the setpoint filter
    if not (math.isfinite(tr) and tr >= 0.0):
        return "setpoint filter %r s must be >= 0 and finite" % tr
    if m.derivative_on == "measurement" and m.setpoint_weight_c != 0.0:
        return "derivative-on measurement with setpoint weight c = %r" % m.setpoint_weight_c
    if m.integral not in ("backward-euler", "forward-euler", "trapezoidal"):
        return "integral '%s' unknown" % m.integral[:80]
    mode = getattr(m, "controller_mode", "")  # "" in the types before the relay autotune
    if mode not in ("", "pid"):
        return ("controller mode '%s': this controller runs the PID only (a relay episode, docs/autotune.md, "
                "needs pidlab-controller or pidlab-controller-c)" % mode[:80])
    return None


class Episode:
    def __init__(self, config):
        self.id = config.episode_id
        self.total_steps = config.total_steps
        self.reference = config.reference
        self.pid = DiscretePid(config.kp, config.ki, config.kd, config.dt_s, config.derivative_filter_s,
                               config.output_min, config.output_max, config.anti_windup,
                               config.back_calculation_gain, config.setpoint_weight_b,
                               config.setpoint_weight_c, config.integral,
                               getattr(config, "setpoint_filter_s", 0.0))
        self.expected = 0  # the next step to compute
        self.last = None  # the last command sent (an lcmt_control_command)


class ControllerRole:
    """transport::Role + ControllerRole: answers PING, acknowledges
    configurations, answers plant outputs."""

    def __init__(self, lcm, prefix, log, print_configs=False):
        self.lcm, self.prefix, self.log = lcm, prefix, log
        self.print_configs = print_configs
        self.episode_id = 0  # current episode, 0 before the first
        self.episode = None
        self.counters = dict(episodes=0, commands=0, foreign=0, duplicates=0, bad_configs=0, conflicts=0,
                             undecodable=0)

    # -- sending
    def publish(self, lane, name, msg):
        msg.utime = now_utime()
        self.lcm.publish(lane, self.prefix + name, msg.encode())

    def ack(self, episode_id):
        r = lcmt_ready()
        r.episode_id = episode_id
        r.step = -1
        r.state = lcmt_ready.ALIVE if episode_id == 0 else lcmt_ready.CONFIG_ACK
        r.role = "controller"
        r.pid = os.getpid()
        r.detail = ""
        self.publish(0, "READY", r)

    # -- receiving: the channel decides the type, the lane must match
    def handle(self, lane, channel, payload):
        if not channel.startswith(self.prefix):
            return
        name = channel[len(self.prefix):]
        handlers = {(0, "EPISODE_CONFIG"): (lcmt_episode_config, self.on_config),
                    (0, "READY"): (lcmt_ready, self.on_ready),
                    (PLANT_OUTPUT_LANE, "PLANT_OUTPUT"): (lcmt_plant_output, self.on_output)}
        entry = handlers.get((lane, name))
        if entry is None:
            return  # a channel this role does not subscribe to
        cls, on_message = entry
        try:
            msg = cls.decode(payload)
        except Exception:  # wrong fingerprint, truncated, absurd lengths: count and ignore
            self.counters["undecodable"] += 1
            return
        on_message(msg)

    def on_ready(self, m):
        if m.state == lcmt_ready.PING:
            self.ack(0)

    def on_config(self, m):
        if m.episode_id == self.episode_id and self.episode_id != 0:
            self.counters["duplicates"] += 1
            self.ack(self.episode_id)  # our first acknowledgement may have been lost
            return
        error = config_error(m)
        if error:
            self.counters["bad_configs"] += 1
            self.log("ignoring configuration of episode %d: %s" % (m.episode_id, error))
            return
        self.episode_id = m.episode_id
        self.counters["episodes"] += 1
        self.episode = Episode(m)
        if self.print_configs:  # what this controller saw: every field by its .lcm name
            print(json.dumps({name: getattr(m, name) for name in m.__slots__}), flush=True)
        self.ack(self.episode_id)

    def on_output(self, m):
        e = self.episode
        if e is None or m.episode_id != e.id:
            self.counters["foreign"] += 1
            return
        if m.step == e.expected and m.step < e.total_steps:
            status, u = e.pid.step(e.reference, m.y)
            c = lcmt_control_command()
            c.episode_id = e.id
            c.step = m.step
            c.t_s = m.t_s
            c.r = e.reference
            c.y = m.y
            # INVALID_INPUT: the C++ sends the 0.0 its u was initialised with.
            c.u = u if u is not None else 0.0
            c.status = status
            e.last = c
            e.expected += 1
            self.counters["commands"] += 1
            self.publish(CONTROL_LANE, "CONTROL", c)
            if m.step + 1 == e.total_steps:
                self.log("episode %d: done, %d commands (re-answered %d)" % (e.id, e.expected,
                                                                            self.counters["duplicates"]))
        elif e.last is not None and m.step == e.last.step:
            # Compared bit for bit, like the C++ memcmp: a different y for a
            # step already answered is not the plant's resend. Never compute
            # from it; repeat the answer, which carries the y it came from.
            if struct.pack("<d", m.y) != struct.pack("<d", e.last.y):
                self.counters["conflicts"] += 1
            else:
                self.counters["duplicates"] += 1  # the plant did not hear us
            self.publish(CONTROL_LANE, "CONTROL", e.last)
        else:
            self.counters["duplicates"] += 1  # an older step, or one ahead: ignore


def main():
    parser = argparse.ArgumentParser(description="pidlab's controller role in Python (docs/protocol.md).")
    parser.add_argument("--lcm-url", default=os.environ.get("PIDLAB_LCM_URL") or DEFAULT_LCM_URL,
                        help="udpm:// URL of the trio (default $PIDLAB_LCM_URL, else %(default)s)")
    parser.add_argument("--channel-prefix", default=os.environ.get("PIDLAB_CHANNEL_PREFIX") or DEFAULT_CHANNEL_PREFIX,
                        help="prefix of every channel (default $PIDLAB_CHANNEL_PREFIX, else PIDLAB_)")
    parser.add_argument("--verbose", "-v", action="store_true", help="print the counters when stopped")
    parser.add_argument("--print-configs", action="store_true",
                        help="print every configuration accepted to stdout, one JSON line of every message field")
    args = parser.parse_args()
    program = "python_controller"

    def log(line):
        sys.stderr.write("%s: %s\n" % (program, line))
        sys.stderr.flush()

    try:
        url = UdpmUrl(args.lcm_url)
    except ValueError as error:
        log("error: %s" % error)
        return 2
    if any(c in args.channel_prefix for c in " \t\n") or len(args.channel_prefix.encode()) > 44:
        log("error: channel prefix '%s' must have no white space and at most 44 bytes" % args.channel_prefix[:80])
        return 2
    try:
        lcm = LcmUdpm(url)
        lcm.listen(0)
        lcm.listen(PLANT_OUTPUT_LANE)
    except OSError as error:
        log("failed: cannot start LCM on '%s': %s (no multicast route? see docs/trio.md)" % (args.lcm_url, error))
        return 1
    role = ControllerRole(lcm, args.channel_prefix, log, args.print_configs)
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    signal.signal(signal.SIGINT, lambda *_: stop.append(1))
    while not stop:
        try:
            for lane, channel, payload in lcm.receive(0.05):
                role.handle(lane, channel, payload)
        except InterruptedError:
            continue
    if args.verbose:
        counters = dict(role.counters, lc03_ignored=lcm.fragments_ignored, malformed=lcm.malformed)
        log(", ".join("%s %d" % kv for kv in counters.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
