"""Every episode field, from what the user types to what the controllers see.

Walks the spec's field list (pidlab.spec_fields: every field marked for the
episode) and follows each field's example value through the house:

  1. the Python keyword: pidlab.evaluate(..., key=example) echoes it in
     result["spec"];
  2. the CLI flag: `pidlab evaluate --FLAG TEXT --backend lcm --json`, run on
     a trio, echoes the same spec, and its IAE and ISE are those of
     pidlab.evaluate in process, bit for bit;
  3. the LCM message: the episode configuration logged by lcm-logger differs
     from its base's;
  4. `pidlab replay --json`: the episode's "config" is that message;
  5. the C and the Python controllers' view: pidlab-controller-c and
     examples/python_controller.py, each in the trio in turn with
     --print-configs, print the same configuration, every field.

A field reaches the episode when some base spec (a linear plant, the
nonlinear stepper, a custom plant) accepts its example and the logged
configuration differs from that base's. Nothing here names a field: a field
added to the spec and the message is walked without touching this test.

Run by episode_fields_test.sh in a private network namespace:
  python3 episode_fields_walk.py BIN_DIR SOURCE_DIR WORK_DIR
"""
import json
import os
import subprocess
import sys

import pidlab

bin_dir, source_dir, work = sys.argv[1:4]
pidlab_cli = os.path.join(bin_dir, "pidlab")
controllers = {
    "c": [os.path.join(bin_dir, "pidlab-controller-c")],
    "python": [sys.executable, os.path.join(source_dir, "examples", "python_controller.py")],
}
url = "udpm://239.255.76.67:7667?ttl=0"
failures = []


def check(name, ok, detail=""):
    print(("ok   " if ok else "FAIL ") + name + ("" if ok else ": " + detail), flush=True)
    if not ok:
        failures.append(name)


BASES = {
    "linear": dict(plant="double_integrator", gains=[2.0, 0.5, 2.0], loop="sampled", horizon=2.0),
    "motor": dict(plant="stepper_nonlinear", gains=[100.0, 50.0, 10.0], loop="sampled", dt=1e-4,
                  sample_time=0.01, horizon=0.05),
    "custom": dict(num=[1.0], den=[1.0, 2.0, 1.0], gains=[2.0, 0.5, 2.0], loop="sampled", horizon=2.0),
}


def flag_words(flag, value):
    """The words a user types for a value, as the flags read them."""
    if isinstance(value, bool):
        return [flag] if value else []
    if isinstance(value, dict):
        return [w for name, x in value.items() for w in (flag, "%s=%r" % (name, x))]
    if isinstance(value, (list, tuple)):
        return [flag, ",".join(repr(x) for x in value)]
    return [flag, str(value)]


def cli_words(spec, flags):
    return [w for key, value in spec.items() for w in flag_words(flags[key], value)]


fields = [f for f in pidlab.spec_fields("evaluate") if f["episode"]]
flags = {f["key"]: f["flag"] for f in pidlab.spec_fields("evaluate")}
check("the spec lists episode fields (%d)" % len(fields), len(fields) >= 30)

# 1. The Python keyword: every combination of field and base that evaluates.
runs = [("base", name, base) for name, base in BASES.items()]
local = [pidlab.evaluate(**base) for base in BASES.values()]
for f in fields:
    accepted = 0
    for name, base in BASES.items():
        spec = dict(base, **{f["key"]: f["example"]})
        try:
            result = pidlab.evaluate(**spec)
        except ValueError:
            continue
        if result["spec"].get(f["key"]) != f["example"]:
            check("pidlab.evaluate echoes %s=%r" % (f["key"], f["example"]), False,
                  "echo %r" % result["spec"].get(f["key"]))
            continue
        accepted += 1
        runs.append((f["key"], name, spec))
        local.append(result)
    check("pidlab.evaluate takes the keyword %s=%r on some base and echoes it" % (f["key"], f["example"]),
          accepted > 0)

# 2. The CLI flags over the trio, once per controller, with the log.
with open(os.path.join(work, "runs.sh"), "w") as script:
    script.write("set -u\n")
    for i, (key, base, spec) in enumerate(runs):
        words = [pidlab_cli, "evaluate", "--backend", "lcm", "--json", "-v"] + cli_words(spec, flags)
        script.write(" ".join("'%s'" % w for w in words) + " >run%d.json 2>run%d.err || echo $? >run%d.rc\n" %
                     (i, i, i))

views = {}
for which, command in controllers.items():
    run_dir = os.path.join(work, which)
    os.makedirs(run_dir)
    env = dict(os.environ, PYTHONPATH=os.environ.get("PYTHONPATH", ""))
    with open(os.path.join(run_dir, "configs.jsonl"), "w") as out, \
            open(os.path.join(run_dir, "controller.err"), "w") as err:
        controller = subprocess.Popen(command + ["--lcm-url", url, "--print-configs"], stdout=out, stderr=err,
                                      cwd=run_dir, env=env)
        launch = subprocess.run([pidlab_cli, "launch", "--roles", "plant,disturbance", "--lcm-url", url, "--log",
                                 "trio.lcm", "--", "bash", os.path.join(work, "runs.sh")], cwd=run_dir,
                                capture_output=True, text=True)
        controller.terminate()
        controller.wait()
    check("%s controller: the trio ran the %d runs" % (which, len(runs)), launch.returncode == 0,
          launch.stderr[-400:])
    results = []
    for i, (key, base, spec) in enumerate(runs):
        path = os.path.join(run_dir, "run%d.json" % i)
        try:
            result = json.load(open(path))
        except (OSError, ValueError):
            rc = open(os.path.join(run_dir, "run%d.rc" % i)).read().strip() if os.path.exists(
                os.path.join(run_dir, "run%d.rc" % i)) else "?"
            check("%s: %s on %s over the trio" % (which, key, base), False,
                  "exit %s: %s" % (rc, open(os.path.join(run_dir, "run%d.err" % i)).read()[-300:]))
            results.append(None)
            continue
        if key != "base":
            echo = result["spec"].get(key)
            if echo != spec[key]:
                check("%s: the flag %s echoes %r" % (which, flags[key], spec[key]), False, "echo %r" % echo)
        # The trio runs what the process computes alone, to the bit.
        if (result["iae"], result["ise"]) != (local[i]["iae"], local[i]["ise"]):
            check("%s: %s on %s over the trio equals pidlab.evaluate" % (which, key, base), False,
                  "IAE %r against %r" % (result["iae"], local[i]["iae"]))
        results.append(result)
    # 4. What replay reads back from the log, by episode id (each run's ids
    # from its -v notes: a run with a disturbance also runs the undisturbed
    # episode).
    replay = subprocess.run([pidlab_cli, "replay", "trio.lcm", "--json"], cwd=run_dir, capture_output=True,
                            text=True)
    episodes = json.loads(replay.stdout)["episodes"] if replay.returncode == 0 else []
    logged = {e["episode_id"]: e.get("config") for e in episodes}
    ids = []
    for i in range(len(runs)):
        notes = open(os.path.join(run_dir, "run%d.err" % i)).read().split("\n")
        ids.append([int(line.split()[3]) for line in notes if line.startswith("pidlab: note: episode ")
                    and line.endswith(" ran")])
    # (A run whose sampled loop is unstable runs no episode: it counts for no
    # field.)
    named = [i for r in ids for i in r]
    check("%s: pidlab replay lists all %d episodes the runs name, with their config" % (which, len(named)),
          len(named) >= len(runs) - 5 and all(logged.get(i) for i in named),
          "%d episodes in the log, rc %d %s" % (len(episodes), replay.returncode, replay.stderr[-200:]))
    # 5. What the controller printed, by episode id.
    seen = {}
    for line in open(os.path.join(run_dir, "configs.jsonl")):
        m = json.loads(line)
        seen[m["episode_id"]] = m
    views[which] = (ids, logged, seen)


def comparable(config):
    """A configuration without the clock and the episode's id, infinities as text."""
    def text(v):
        if isinstance(v, float) and (v != v or v in (float("inf"), float("-inf"))):
            return {float("inf"): "inf", float("-inf"): "-inf"}.get(v, "nan")
        return v
    return {k: ([text(x) for x in v] if isinstance(v, list) else text(v))
            for k, v in config.items() if k not in ("utime", "episode_id")}


for which, (ids, logged, seen) in views.items():
    base_config = {}
    reached = {}
    for (key, base, spec), run_ids in zip(runs, ids):
        configs = []
        for episode_id in run_ids:
            config = logged.get(episode_id)
            view = seen.get(episode_id)
            if config is None or view is None:
                check("%s: episode %d of %s on %s is logged and printed" % (which, episode_id, key, base), False,
                      "logged %s, printed %s" % (config is not None, view is not None))
                continue
            if comparable(view) != comparable(config):
                diff = [k for k in config if comparable(config).get(k) != comparable(view).get(k)]
                check("%s controller saw %s on %s as logged" % (which, key, base), False, "differ: %s" % diff)
                continue
            configs.append(comparable(config))
        if key == "base":
            base_config[base] = configs[0] if configs else None
        elif any(c != base_config.get(base) for c in configs):
            reached[key] = True
    for f in fields:
        check("%s: %s reaches the message, replay and the %s controller" % (which, f["key"], which),
              reached.get(f["key"], False), "no base's configuration changed")

print("%d failures" % len(failures))
sys.exit(1 if failures else 0)
