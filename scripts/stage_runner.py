"""The stage runner of scripts/experiment.py: a stage cache, subprocesses and signals.

A stage is one step of a pipeline: a name, the parameters that decide whether its cached
outputs are still valid, the names of the stages it depends on, an action and a check of its
outputs.  Runner.execute runs a list of stages in order.  Every stage records its status,
parameters, input stamps and commands in a JSON file (its record_file, one object keyed by stage
name); a re-run skips a stage whose record is "done" with the same parameters and input stamps
and whose outputs pass the check, and recomputes it otherwise, which gives its outputs a new
stamp and so recomputes every stage that depends on it.  A stage left "running" (the run was
stopped) with the same parameters and inputs is marked resumable (stage.resume).

Commands run as subprocesses with their output appended to LOG_DIR/<stage>.log; on Ctrl-C
the running command gets SIGINT (unjam then saves its state) and 60 s to stop.  A failed
command or a stage whose outputs do not check raises StageError.

A stage's record gives its wall time (seconds) and the CPU time of its commands (cpu_seconds:
user + system of the finished subprocesses, all their threads); a stage resumed after a stop
records the time of the resumed part only.
"""

import json
import os
import re
import shlex
import signal
import subprocess
import time
import uuid


class StageError(Exception):
    pass


def read_json(path):
    """The JSON in path, or None if it is missing or does not parse."""
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def write_json(path, obj):
    """obj to path atomically (a temporary file, then os.replace), indented, keys sorted."""
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(obj, f, indent=1, sort_keys=True)
        f.write("\n")
    os.replace(tmp, path)


def children_cpu():
    """User + system CPU seconds of this process's finished (waited-for) child processes."""
    t = os.times()
    return t.children_user + t.children_system


def nonempty(path):
    return os.path.isfile(path) and os.path.getsize(path) > 0


def quote(cmd):
    """A command as one shell-quoted line."""
    return " ".join(shlex.quote(str(c)) for c in cmd)


class Stage:
    """One step: name, parameters (compared for caching), inputs, outputs check, action."""

    def __init__(self, name, what, record_file, params, run, check, deps=(), commands=()):
        self.name = name
        self.what = what
        self.record_file = record_file   # stage.json holding this stage's record under `name`
        self.params = params
        self.run = run                   # run(stage, record) -> None
        self.check = check               # check() -> bool: outputs exist and read
        self.deps = list(deps)
        self.commands = list(commands)   # filled as run() goes, for the record / errors
        self.resume = False              # set by Runner.execute: a stopped run of the same stage
        self.record = None               # set by Runner.execute: the record being written


class Runner:
    """Runs stages in order, skipping the cached ones; commands run in `cwd`, their output
    appended to log_dir/<stage>.log."""

    def __init__(self, out, unjam, threads, log_dir, launcher=(), cwd=None):
        self.out = out
        self.cwd = cwd
        self.launcher = list(launcher)   # e.g. ["mpirun", "-n", "4"]: for the probe campaigns
        self.unjam = unjam
        self.threads = threads
        self.log_dir = log_dir
        self.stamps = {}      # stage name -> stamp of its current outputs
        # (name, what, action, seconds this run, seconds when computed, CPU seconds when
        # computed: user + system time of the stage's commands and their children)
        self.timings = []
        self.t0 = time.time()

    def records(self, path):
        return read_json(path) or {}

    def save_record(self, stage, rec):
        recs = self.records(stage.record_file)
        recs[stage.name] = rec
        os.makedirs(os.path.dirname(stage.record_file), exist_ok=True)
        write_json(stage.record_file, recs)

    def execute(self, stages):
        n = len(stages)
        for i, st in enumerate(stages, 1):
            inputs = {d: self.stamps[d] for d in st.deps}
            old = self.records(st.record_file).get(st.name)
            prefix = f"[{i}/{n}] {st.name}: {st.what}"
            if (old and old.get("status") == "done" and old.get("params") == st.params
                    and old.get("inputs") == inputs and st.check()):
                self.stamps[st.name] = old["stamp"]
                self.timings.append((st.name, st.what, "cached", 0.0, old.get("seconds", 0.0),
                                     old.get("cpu_seconds")))
                print(f"{prefix} ... skipped (cached)  [{self.elapsed()}]", flush=True)
                continue
            print(f"{prefix} ... running  [{self.elapsed()}]", flush=True)
            resume = bool(old and old.get("status") == "running"
                          and old.get("params") == st.params and old.get("inputs") == inputs)
            rec = {"status": "running", "params": st.params, "inputs": inputs,
                   "commands": [], "started": time.strftime("%Y-%m-%dT%H:%M:%S")}
            t, cpu0 = time.time(), children_cpu()
            st.resume = resume
            st.record = rec
            self.save_record(st, rec)
            st.run(st)
            if not st.check():
                raise StageError(f"stage {st.name}: the outputs are missing or unreadable after "
                                 f"the commands\n  " + "\n  ".join(rec["commands"]))
            dt, cpu = time.time() - t, children_cpu() - cpu0
            rec.update(status="done", seconds=round(dt, 3), cpu_seconds=round(cpu, 3),
                       stamp=uuid.uuid4().hex)
            self.save_record(st, rec)
            self.stamps[st.name] = rec["stamp"]
            self.timings.append((st.name, st.what, "ran", dt, dt, cpu))
            print(f"{prefix} ... done in {dt:.1f} s  [cpu {cpu:.1f} s; {self.elapsed()}]",
                  flush=True)

    def elapsed(self):
        return f"{time.time() - self.t0:.1f} s elapsed"

    def call(self, stage, cmd):
        """Run one command of `stage`; its output goes to OUT/logs/<stage>.log."""
        cmd = [str(c) for c in cmd]
        stage.record["commands"].append(quote(cmd))
        self.save_record(stage, stage.record)
        os.makedirs(self.log_dir, exist_ok=True)
        log = os.path.join(self.log_dir, re.sub(r"[^A-Za-z0-9.=-]+", "_", stage.name) + ".log")
        with open(log, "a") as f:
            f.write(f"$ {quote(cmd)}\n")
            f.flush()
            proc = subprocess.Popen(cmd, stdout=f, stderr=subprocess.STDOUT, cwd=self.cwd)
            try:
                rc = proc.wait()
            except KeyboardInterrupt:
                # let unjam save its state (pack: --resume; probe: its checkpoint)
                proc.send_signal(signal.SIGINT)
                try:
                    proc.wait(timeout=60)
                except subprocess.TimeoutExpired:
                    proc.kill()
                raise
        if rc != 0:
            with open(log) as f:
                tail = "".join(f.readlines()[-15:])
            raise StageError(f"stage {stage.name} failed (exit status {rc}) in the command\n"
                             f"  {quote(cmd)}\nlast lines of {log}:\n{tail}")

    def unjam_cmd(self, *args, threads_flag=True, mpi=False):
        cmd = (self.launcher if mpi else []) + [self.unjam] + [str(a) for a in args]
        if threads_flag and self.threads:
            cmd += ["--threads", str(self.threads)]
        return cmd
