#!/usr/bin/env bash
# The house (docs/architecture.md), checked on the build's own dependency
# graph (cmake --graphviz) and on the sources:
#  - every pidlab library links only libraries on a lower level;
#  - pidlab-plant, pidlab-controller and pidlab-disturbance link none of Ceres,
#    the optimisers, the evaluation, the analysis, the tuning, the report,
#    the plotting code or the launcher;
#  - no header of a higher folder is included from a lower one;
#  - the tuner's optim, evaluation, analysis and tune include no LCM,
#    transport or episode client header, and only pidlab/<x>/ headers of
#    their own level or below;
#  - tools/ holds front ends only: no library's include/ folder;
#  - nothing in the repository reads the folder beside it (the repository
#    stands alone).
# usage: architecture_test.sh SOURCE_DIR BUILD_DIR
set -uo pipefail
src=$1 build=$2
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
(cd "$tmp" && cmake --graphviz=deps.dot "$build" >/dev/null 2>&1) || { echo "FAIL cmake --graphviz"; exit 1; }
python3 - "$tmp/deps.dot" "$src" <<'PY'
import os, re, subprocess, sys
dot, src = sys.argv[1], sys.argv[2]
# Levels of the house, bottom (0) to top. A library may link only lower levels.
level = {
    'pidlab_lcmtypes': 0, 'pidlab_controller': 0, 'pidlab_status': 0,
    'pidlab_spec': 1, 'pidlab_plant_sim': 1, 'pidlab_optim': 1, 'pidlab_plot': 3,
    'pidlab_server': 2,
    'pidlab_io': 2, 'pidlab_transport': 2, 'pidlab_evaluation': 2, 'pidlab_controller_export': 2,
    'pidlab_autotune': 2,
    'pidlab_role_main': 3, 'pidlab_plant_roles': 3, 'pidlab_controller_role': 3, 'pidlab_analysis': 3,
    'pidlab_monitor': 3,
    'pidlab_tune': 4, 'pidlab_identify': 4, 'pidlab_episode_client': 4, 'pidlab_log_reader': 4, 'pidlab_pil': 4,
    'pidlab_tuner': 5, 'pidlab_results': 5, 'pidlab_identify_json': 6, 'pidlab_replay': 5, 'pidlab_launcher': 5,
    'pidlab_report': 6, 'pidlab_replay_json': 6, 'pidlab_autotune_json': 6, 'pidlab_live_json': 7, 'pidlab_figures': 6, 'pidlab_cli': 7,
    'pidlab': 8, 'pidlab_python': 8,
}
labels, edges = {}, []
for line in open(dot):
    m = re.match(r'\s*"(node\d+)" \[ label = "([^"\\]+)', line)
    if m: labels[m.group(1)] = m.group(2)
    m = re.match(r'\s*"(node\d+)" -> "(node\d+)"', line)
    if m: edges.append((m.group(1), m.group(2)))
deps = {}
for a, b in edges: deps.setdefault(labels[a], set()).add(labels[b])
failures = 0
def fail(msg):
    global failures
    failures += 1
    print('FAIL ' + msg)
missing = [t for t in level if t not in labels.values()]
if missing: fail('targets not in the graph: ' + ', '.join(missing))
for a, bs in sorted(deps.items()):
    if a not in level: continue
    for b in sorted(bs):
        if b.startswith('pidlab') and b in level and level[b] >= level[a]:
            fail(f'{a} (level {level[a]}) links {b} (level {level[b]}): a dependency that does not point down')
        if b.startswith('pidlab') and b not in level:
            fail(f'{a} links {b}, which has no level in this test')
def closure(t):
    seen, todo = set(), [t]
    while todo:
        for d in deps.get(todo.pop(), ()):
            if d not in seen: seen.add(d); todo.append(d)
    return seen
forbidden = {'Ceres::ceres', 'pidlab_optim', 'pidlab_evaluation', 'pidlab_analysis', 'pidlab_tune', 'pidlab_tuner',
             'pidlab_report', 'pidlab_plot', 'pidlab_launcher',
             'pidlab_replay', 'pidlab_log_reader', 'pidlab_episode_client'}
for exe in ('pidlab-plant', 'pidlab-controller', 'pidlab-disturbance'):
    if exe not in deps: fail(f'{exe} not in the graph'); continue
    bad = sorted(closure(exe) & forbidden)
    if bad: fail(f'{exe} links {", ".join(bad)}')
    else: print(f'ok   {exe} links only ' + ', '.join(sorted(d for d in closure(exe) if d.startswith("pidlab"))))
# Sources: a folder includes only headers of its own level or below.
header_level = {'io': 2, 'spec': 1, 'plant_sim': 1, 'controller': 0, 'optim': 1, 'plot': 3, 'server': 2, 'transport': 2, 'evaluation': 2, 'controller_export': 2,
                'autotune': 2,
                'analysis': 3, 'monitor': 3, 'tune': 4, 'identify': 4, 'episode_client': 4, 'replay': 4, 'results': 5, 'launcher': 5, 'report': 6,
                'pil': 4,
                'figures': 6}
lib_dirs = {'io': 2, 'spec': 1, 'server': 2, 'transport': 2, 'tuner/optim': 1, 'tuner/evaluation': 2, 'tuner/analysis': 3, 'monitor': 3,
            'tuner/autotune': 2,
            'tuner/tune': 4, 'tuner/identify': 4, 'tuner/episode_client': 4, 'replay': 5, 'launcher': 5,
            'plot': 3, 'results': 5, 'report': 6, 'figures': 6, 'controller/pil': 4}
for d, lv in lib_dirs.items():
    for root, _, files in os.walk(os.path.join(src, d)):
        for f in files:
            for inc in re.findall(r'#include "pidlab/(\w+)/', open(os.path.join(root, f)).read()):
                if header_level.get(inc, 0) > lv:
                    fail(f'{os.path.relpath(os.path.join(root, f), src)} includes a pidlab/{inc}/ header from above')
# The tuner's libraries other than the episode client (identify included): no LCM (<lcm/...>, a
# message's lcmt_*.hpp), no transport, no episode client; every pidlab/<x>/
# header they include is of their own level or below (and has a level).
for d in ('optim', 'evaluation', 'analysis', 'tune', 'identify', 'autotune'):
    lv = header_level[d]
    for root, _, files in os.walk(os.path.join(src, 'tuner', d)):
        for f in files:
            path = os.path.join(root, f)
            rel = os.path.relpath(path, src)
            for inc in re.findall(r'#include\s*[<"]([^>"]+)[>"]', open(path).read()):
                if inc.startswith('lcm/') or re.search(r'(^|/)lcmt_\w*\.hpp$', inc):
                    fail(f'{rel} includes the LCM header {inc}')
                m = re.match(r'pidlab/(\w+)/', inc)
                if not m: continue
                if m.group(1) in ('transport', 'episode_client'):
                    fail(f'{rel} includes {inc}: only the episode client may use the transport')
                elif m.group(1) not in header_level:
                    fail(f'{rel} includes {inc}, whose folder has no level in this test')
                elif header_level[m.group(1)] > lv:
                    fail(f'{rel} (level {lv}) includes {inc} (level {header_level[m.group(1)]}) from above')
# The live monitor watches the trio for the server, and holds the live
# scope's state (LiveScope): it includes no server header and nothing of
# tools/ (the page's requests are tools/serve_live.cc's, the JSON of its
# status results/'s). It follows a relay episode as the controller runs it
# (docs/autotune.md): the relay's state machine and its estimates, both below it.
for root, _, files in os.walk(os.path.join(src, 'monitor')):
    for f in files:
        path = os.path.join(root, f)
        for inc in re.findall(r'#include\s*"([^"]+)"', open(path).read()):
            if (not re.match(r'pidlab/(monitor|transport|autotune)/', inc) and
                    inc not in ('pidlab/spec/status.h', 'pidlab/controller/relay.h')):
                fail(f'{os.path.relpath(path, src)} includes "{inc}": the monitor includes only its own, the transport\'s and the relay autotune\'s headers (and the one status type)')
# tools/ holds the front ends only (the pidlab command, the Python module, the
# page's request handlers): no library with headers of its own lives there.
for root, dirs, _ in os.walk(os.path.join(src, 'tools')):
    if 'include' in dirs:
        fail(f'{os.path.relpath(os.path.join(root, "include"), src)}: a library in tools/, which holds only front ends')
# plant_sim and controller models (not their roles) include no transport header.
for d in ('plant_sim', 'controller'):
    for root, _, files in os.walk(os.path.join(src, d)):
        for f in files:
            if 'role' in f or f.endswith('_main.cc'): continue
            text = open(os.path.join(root, f)).read()
            if re.search(r'#include "pidlab/(transport|optim|evaluation|analysis|tune|episode_client|replay|launcher)/', text) or 'lcm' in re.findall(r'#include <(\w+)', text):
                fail(f'{os.path.relpath(os.path.join(root, f), src)} is a model but includes LCM or a higher layer')
# One episode shape: the evaluation's loop and the trio's episode embed
# EpisodeShape (plant_sim/episode_shape.h) instead of copying its fields, and
# the episode configuration's frozen copies are generated from its
# "//@frozen" lines (cmake/LcmGen.cmake), never kept by hand in lcmtypes/.
for header, shape in (('tuner/evaluation/include/pidlab/evaluation/closed_loop.h', 'struct LoopOptions : EpisodeShape'),
                      ('transport/include/pidlab/transport/episode_spec.h', 'struct EpisodeSpec : EpisodeShape')):
    if shape not in open(os.path.join(src, header)).read():
        fail(f'{header}: no "{shape}"')
for f in os.listdir(os.path.join(src, 'lcmtypes')):
    if re.match(r'lcmt_.*_v\d+\.lcm$', f):
        fail(f'lcmtypes/{f}: a frozen copy kept by hand (mark "//@frozen" in the type instead)')
frozen = [int(n) for n in re.findall(r'//@frozen lcmt_episode_config_v(\d+)', open(os.path.join(src, 'lcmtypes/lcmt_episode_config.lcm')).read())]
if len(frozen) < 4 or frozen != list(range(1, len(frozen) + 1)):
    fail('lcmtypes/lcmt_episode_config.lcm: expected //@frozen lines of v1, v2, ... in order, at least v1..v4: %s' % frozen)
# Nothing in the repository names the folder beside it.
beside = '..' + '/' + 'shared'
hits = subprocess.run(['git', '-C', src, 'grep', '-l', '-F', beside, '--', '.'],
                      capture_output=True, text=True).stdout.split()
if hits: fail('these files name ' + beside + ': ' + ' '.join(hits))
print(f'{len(deps)} targets checked, {failures} failures')
sys.exit(1 if failures else 0)
PY
