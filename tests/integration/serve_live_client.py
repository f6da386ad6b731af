"""The client side of tests/integration/serve_live_test.sh: watches `pidlab serve
--lcm-url` over its WebSocket while `pidlab evaluate --backend lcm` runs one
episode on the trio, and checks the live scope's contract (docs/live.md).
With auth, a forged EPISODE_CONFIG (a well-formed message with a wrong MAC)
is sent to the trio's group first: it must not be shown, and be counted.
With realtime (a trio paced by `pidlab launch --realtime`), the episode's
realtime in live_status must equal evaluate --json's realtime object.
usage: serve_live_client.py PORT WORKDIR plain|auth|realtime PYTHON_MESSAGES_DIR PIDLAB EVALUATE_ARGS...
(the command gets --json --trajectory-csv FILE appended)"""
import json, math, os, socket, struct, subprocess, sys, time
from serve_client import WebSocket

port, work, mode, messages_dir, evaluate_command = int(sys.argv[1]), sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5:]
# evaluate_command: the binary, then docs/live.md's arguments after 'pidlab'
failures = 0
FORGED_ID = 777


def check(name, ok):
    global failures
    print(('ok   ' if ok else 'FAIL ') + name)
    if not ok: failures += 1


def frame(payload):
    """(kind, header dict, arrays) of a binary frame."""
    magic, kind = struct.unpack_from('<II', payload, 0)
    assert magic == 0x31564C50, hex(magic)
    names = ['episode_id', 'first_step', 'steps', 'columns', 'dt_s', 'total_steps', 'steps_done', 'dropped_frames']
    h = dict(zip(names, struct.unpack_from('<8d', payload, 8)))
    if kind == 1:
        c = int(h['columns'])
        arrays = [struct.unpack_from('<%df' % c, payload, 72 + 4 * c * i) for i in range(6)]
    else:
        s = int(h['steps'])
        arrays = [struct.unpack_from('<%dd' % s, payload, 72 + 8 * s * i) for i in range(3)]
    return kind, h, arrays


def send_forged_config():
    """A well-formed lcmt_episode_config on PIDLAB_EPISODE_CONFIG with 32 random
    bytes for its MAC, as LCM's UDP short message (docs/live.md)."""
    sys.path.insert(0, messages_dir)
    from pidlab import lcmt_episode_config
    m = lcmt_episode_config()
    m.episode_id, m.plant_name, m.total_steps, m.dt_s = FORGED_ID, 'forged', 10, 0.01
    payload = m.encode() + os.urandom(32)
    datagram = struct.pack('>II', 0x4c433032, 0) + b'PIDLAB_EPISODE_CONFIG\0' + payload
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)
    s.sendto(datagram, ('239.255.76.67', 7667))
    s.close()


def same_bits(a, b):
    return len(a) == len(b) and all(struct.pack('<d', x) == struct.pack('<d', y) for x, y in zip(a, b))


ws = WebSocket(port)
ws.s.settimeout(30)
info = ws.ask({'type': 'server_info'})
check('server_info says live, with the URL, prefix and auth', info.get('live') is True and info.get('lcm_url') and
      info.get('channel_prefix') == 'PIDLAB_' and info.get('auth') is (mode == 'auth'))
bad = ws.ask({'type': 'live_subscribe', 'columns': 5})
check('live_subscribe with 5 columns is refused naming them', 'columns 5' in bad.get('error', ''))
ws.send(json.dumps({'type': 'live_subscribe', 'columns': 200}))

if mode == 'auth': send_forged_config()
# One episode over the trio (docs/live.md's: 2001 steps at dt = 1 ms).
evaluate = subprocess.Popen(evaluate_command + ['--json', '--trajectory-csv', work + '/trajectory.csv'],
                            stdout=subprocess.PIPE)
views, final, status, subscribed = [], None, None, False
deadline = time.monotonic() + 60
while time.monotonic() < deadline and (final is None or status is None or
                                       not any(e['status'] == 'complete' for e in status['episodes'])):
    op, payload = ws.recv()
    if op == 2:
        kind, h, arrays = frame(payload)
        if kind == 1: views.append((h, arrays))
        else: final = (h, arrays)
    elif op == 1:
        m = json.loads(payload)
        if m.get('type') == 'live_subscribed': subscribed = True
        if m.get('type') == 'live_status': status = m
evaluate_out, _ = evaluate.communicate(timeout=60)
check('pidlab evaluate --backend lcm ran the episode', evaluate.returncode == 0)
check('live_subscribe is answered live_subscribed', subscribed)
check('view frames (kind 1) came while the episode ran', len(views) >= 1)
check('a view has at most the columns asked for, and min <= max',
      all(int(h['columns']) <= 200 and all(lo <= hi for lo, hi in zip(a[0], a[1]) if lo == lo) for h, a in views))
check('the final data frame (kind 2) came', final is not None)
# --trajectory-csv holds steps 0..total_steps-1 (the chunks' doubles, %.17g);
# the episode has y at total_steps too, and there u and n are NaN.
rows = [line.split(',') for line in open(work + '/trajectory.csv').read().split('\n')[1:] if line]
steps = len(rows) + 1
y = [float(r[3]) for r in rows]
u = [float(r[4]) for r in rows]
n = [float(r[5]) for r in rows]
if final:
    h, (fy, fu, fn) = final
    check('the final frame covers steps 0..total_steps', int(h['first_step']) == 0 and int(h['steps']) == steps and
          int(h['total_steps']) == steps - 1 and int(h['steps_done']) == steps)
    check('its y equals the trajectory bit for bit', same_bits(fy[:-1], y) and math.isfinite(fy[-1]))
    check('its u and n equal the trajectory bit for bit (steps 0..total_steps-1)',
          same_bits(fu[:-1], u) and same_bits(fn[:-1], n))
    check('u and n at total_steps are NaN', math.isnan(fu[-1]) and math.isnan(fn[-1]))
ep = status['episodes'][-1] if status and status['episodes'] else {}
check('live_status shows the episode complete with every step',
      ep.get('status') == 'complete' and ep.get('steps_done') == steps and ep.get('plant') == 'oscillator' and
      ep.get('gains') == [2, 1, 1.5] and ep.get('total_steps') == steps - 1)
evaluated = json.loads(evaluate_out) if evaluate.returncode == 0 else {}
if mode == 'realtime':
    check('a paced episode shows the realtime object evaluate --json prints, exactly',
          'realtime' in evaluated and ep.get('realtime') == evaluated['realtime'])
else:
    check('an unpaced episode shows realtime null', 'realtime' not in evaluated and ep.get('realtime') is None)
roles = status['health']['roles'] if status else {}
check('live_status hears the plant, controller, disturbance and client',
      all(roles.get(r, {}).get('last_heard_s') is not None for r in ('plant', 'controller', 'disturbance', 'client')))
if mode == 'auth':
    check('the forged configuration is not shown and is counted unauthenticated',
          status and all(e['episode_id'] != FORGED_ID for e in status['episodes']) and
          status['health']['unauthenticated'] >= 1)
else:
    check('the health counts received messages and no forged ones',
          status and status['health']['received'] > 0 and status['health']['unauthenticated'] == 0)

check('live_status gives each id as exact decimal text too (JavaScript holds 53 bits)',
      ep.get('episode_id_text') == str(ep.get('episode_id')) and
      status.get('selected_episode_id_text') == str(ep.get('episode_id')))
ws.send(json.dumps({'type': 'live_select', 'episode_id': ep.get('episode_id_text', '')}))
while True:
    op, payload = ws.recv()
    if op == 1 and json.loads(payload).get('type') in ('live_selected', None): break
check('live_select takes the id as its text', json.loads(payload).get('episode_id') == ep.get('episode_id'))
# live_data (the id as text): the same bytes as the final frame, never dropped.
ws.send(json.dumps({'type': 'live_data', 'episode_id': ep.get('episode_id_text', '')}))
data = None
while data is None:
    op, payload = ws.recv()
    if op == 2 and frame(payload)[0] == 2: data = frame(payload)
check('live_data answers the whole episode, equal to the final frame', final and same_bits(data[2][0], final[1][0]))
ws.send(json.dumps({'type': 'live_data', 'episode_id': 12345}))
while True:
    op, payload = ws.recv()
    if op == 1 and 'error' in json.loads(payload): break
check('live_data of an unknown episode is refused', '12345' in json.loads(payload)['error'])

# run_on_trio: the trio's y equals the in-process prediction bit for bit.
spec = {'plant': 'oscillator', 'gains': [2, 1, 1.5], 'dt': 0.001, 'horizon': 1}
ws.send(json.dumps({'type': 'run_on_trio', 'spec': spec}))
started = result = None
deadline = time.monotonic() + 60
while result is None and time.monotonic() < deadline:
    op, payload = ws.recv()
    if op != 1: continue
    m = json.loads(payload)
    if m.get('type') == 'run_on_trio_started': started = m
    if m.get('type') in ('trio_result', 'trio_error'): result = m
check('run_on_trio is answered run_on_trio_started', started is not None)
check('run_on_trio gives trio_result, bit_identical, on the sampled loop',
      result and result.get('type') == 'trio_result' and result.get('bit_identical') is True and
      result.get('max_abs_difference') == 0 and result.get('loop') == 'sampled' and
      result['result'].get('backend') == 'lcm' and result['prediction'].get('backend') == 'local')
if result and result.get('type') != 'trio_result': print(result)
ws.send(json.dumps({'type': 'live_unsubscribe'}))
while True:
    op, payload = ws.recv()
    if op == 1 and json.loads(payload).get('type') == 'live_unsubscribed': break
check('live_unsubscribe is answered live_unsubscribed', True)
sys.exit(1 if failures else 0)
