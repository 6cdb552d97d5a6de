"""Kill anklelab commands at random points and check that no output is ever partial or mixed.

Each *job* is one command writing one output (a file or a run directory), in two variants (A
and B: another seed or input) whose complete outputs are recorded first by uninterrupted runs.
Then, again and again, a random job is started and killed with SIGKILL at a random moment, and
its output must be absent or *exactly* the complete output of variant A or B: a directory must
hold the files its ``run.json`` lists, with their hashes, and nothing else. Temporaries a killed
run leaves (hidden, named after its process) must be gone after the next run. Two writers
started together on one output must never mix (the second stops at once on the lock), and
SIGTERM must end a run with its temporaries removed.

Run the full version as a script (the test suite runs a short one)::

    python -m tests.kill_runs --kills 60 --pairs 6 --terms 6 --seed 0
"""

from __future__ import annotations

import argparse
import collections
import hashlib
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from anklelab._atomic import is_temporary
from anklelab._runs import RUN_FILE, RunManifest

ENTRY = "from anklelab.cli import run; run()"
LOCKED = "is writing it (lock"


@dataclass(frozen=True)
class Job:
    """A command writing ``output`` (relative to the work directory), in variants A and B."""

    name: str
    output: str
    args: dict[str, list[str]]  # variant -> arguments after `anklelab`
    needs: str = ""  # the inputs it reads: "twin", "noise" or "ident" (see `prepare`)


def _variants(args: list[str], option: str, a: str, b: str) -> dict[str, list[str]]:
    return {"A": [*args, option, a, "--force"], "B": [*args, option, b, "--force"]}


def jobs() -> list[Job]:
    """simulate, import, analyze and identify, each writing one output in two variants."""
    sim = ["simulate", "perturberator", "--trials-per-point", "1", "--unperturbed", "2"]
    sim += ["--no-bench"]
    analyze = ["analyze", "baseA.h5", "--out", "an", "--settings", "quick.toml"]
    filters = ["identify", "platform-filters", "baseA", "--out", "filters.json"]
    friction = ["identify", "friction", "ident", "--out", "fr"]
    ident = ["simulate", "capstan-ident", "--out", "ci"]
    return [
        Job("simulate h5", "sim.h5", _variants([*sim, "--out", "sim.h5"], "--seed", "1", "2")),
        Job(
            "simulate dir",
            "simdir",
            _variants([*sim, "--out", "simdir", "--format", "dir"], "--seed", "1", "2"),
        ),
        Job(
            "import",
            "imp.h5",
            {v: ["import", f"noise{v}", "--out", "imp.h5", "--force"] for v in "AB"},
            "noise",
        ),
        Job("analyze", "an", _variants(analyze, "--seed", "1", "2"), "twin"),
        Job(
            "identify platform-filters",
            "filters.json",
            _variants(filters, "--fit-trial", "0", "1"),
            "twin",
        ),
        Job("identify friction", "fr", _variants(friction, "--min-speed", "10", "12"), "ident"),
        Job("simulate capstan-ident", "ci", _variants(ident, "--seed", "1", "2")),
    ]


def prepare(root: Path, needs: set[str]) -> None:
    """The inputs ``needs`` asks for: ``twin``, a small twin session (directory ``baseA`` and
    file ``baseA.h5``) and quick analysis settings; ``noise``, two sessions of noise
    (``noiseA``, ``noiseB``); ``ident``, an identification directory."""
    from anklelab.data import save_session
    from anklelab.data._synthetic import random_session

    if "twin" in needs:
        from anklelab.experiments import simulate_perturberator

        session = simulate_perturberator(
            trials_per_point=3, n_unperturbed=6, n_calibration=2, bench=False, seed=11
        )
        save_session(session, root / "baseA", format="dir")
        save_session(session, root / "baseA.h5")
        (root / "quick.toml").write_text("bootstrap_reps = 5\n")
    if "noise" in needs:
        for variant, seed in (("A", 1), ("B", 2)):
            session = random_session(n_walking=20, n_samples=500, seed=seed)
            save_session(session, root / f"noise{variant}", format="dir")
    if "ident" in needs:
        from anklelab.data.capstan_ident import write_ident_directory
        from anklelab.experiments.capstan_ident import simulate_ident

        write_ident_directory(simulate_ident(seed=4), root / "ident")


def start(root: Path, args: list[str]) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-c", ENTRY, *args],
        cwd=root,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def fingerprint(path: Path) -> str | None:
    """``None`` if absent; a hash of the complete output; ``"broken: ..."`` otherwise.

    A directory must hold exactly the files its run manifest lists, each with its SHA-256; its
    fingerprint leaves out ``run.json`` itself (its run id differs from run to run).
    """
    if not os.path.lexists(path):
        return None
    if path.is_file():
        return _sha256(path)
    try:
        manifest = RunManifest.load(path)
    except Exception as exc:  # reported, not raised: the harness counts every failure
        return f"broken: {exc}"
    if manifest is None:
        return "broken: a directory without run.json"
    on_disk = {p.relative_to(path).as_posix() for p in path.rglob("*") if p.is_file()}
    if on_disk != {*manifest.files, RUN_FILE}:
        return f"broken: files {sorted(on_disk ^ {*manifest.files, RUN_FILE})} differ from run.json"
    for name, entry in manifest.files.items():
        if _sha256(path / name) != entry["sha256"]:
            return f"broken: {name} differs from run.json"
    listing = "\n".join(f"{n} {e['sha256']}" for n, e in sorted(manifest.files.items()))
    return hashlib.sha256(listing.encode()).hexdigest()


def leftovers(root: Path) -> list[str]:
    """Hidden temporaries and lock files in ``root``."""
    return sorted(
        p.name for p in root.iterdir() if is_temporary(p.name) or p.name.endswith(".anklelab.lock")
    )


@dataclass
class Tally:
    references: dict[tuple[str, str], str] = field(default_factory=dict)
    durations: dict[tuple[str, str], float] = field(default_factory=dict)
    outcomes: collections.Counter[str] = field(default_factory=collections.Counter)
    failures: list[str] = field(default_factory=list)
    stale_after_kill: int = 0

    def fail(self, message: str) -> None:
        self.failures.append(message)
        print("FAIL", message, flush=True)


def complete_run(root: Path, job: Job, variant: str, tally: Tally) -> None:
    began = time.monotonic()
    proc = start(root, job.args[variant])
    _, err = proc.communicate()
    tally.durations[job.name, variant] = time.monotonic() - began
    if proc.returncode != 0:
        tally.fail(f"{job.name} {variant}: exit {proc.returncode}: {err.strip()[-300:]}")
    found = fingerprint(root / job.output)
    reference = tally.references.setdefault((job.name, variant), found)
    if found != reference:
        tally.fail(f"{job.name} {variant}: not reproducible ({found} != {reference})")


def classify(root: Path, job: Job, tally: Tally) -> str:
    found = fingerprint(root / job.output)
    if found is None:
        return "absent"
    for variant in "AB":
        if found == tally.references[job.name, variant]:
            return variant
    tally.fail(f"{job.name}: output is neither absent nor a complete run: {found}")
    return "broken"


def kill_once(root: Path, job: Job, rng: random.Random, tally: Tally) -> None:
    variant = rng.choice("AB")
    duration = tally.durations[job.name, variant]
    # half the kills anywhere in the run, half in its last 40 % (where it writes)
    delay = rng.uniform(0, 1.05) if rng.random() < 0.5 else rng.uniform(0.6, 1.05)
    before = classify(root, job, tally)
    proc = start(root, job.args[variant])
    time.sleep(delay * duration)
    finished = proc.poll() is not None
    proc.kill()
    proc.communicate()
    after = classify(root, job, tally)
    if after != "broken" and after not in (before, variant):  # absent: the old one was lost
        tally.fail(f"{job.name}: killed run of {variant} left {after} (before: {before})")
    moment = "after it ended" if finished else "killed"
    tally.outcomes[f"{moment}: {'unchanged' if after == before else 'replaced'}"] += 1
    tally.stale_after_kill += len(leftovers(root))


def concurrent_pair(root: Path, job: Job, rng: random.Random, tally: Tally) -> None:
    """Two writers of one output: started together, or the second once the first holds the
    lock. The second must stop at once on the lock, or (if the first was done) replace the
    output whole."""
    together = rng.random() < 0.5
    lock = root / f".{job.output}.anklelab.lock"
    first = start(root, job.args["A"])
    if not together:
        while first.poll() is None and not lock.exists():
            time.sleep(0.01)
    second = start(root, job.args["B"])
    results = [(p.wait(), p.stderr.read()) for p in (first, second)]
    locked = sum(code == 2 and LOCKED in err for code, err in results)
    ok = sum(code == 0 for code, _ in results)
    if ok + locked != 2 or ok == 0:
        tally.fail(f"{job.name}: concurrent writers ended {[(c, e[-200:]) for c, e in results]}")
    when = "together" if together else "second once the first held the lock"
    tally.outcomes[f"concurrent ({when}): {ok} wrote, {locked} refused on the lock"] += 1
    classify(root, job, tally)


def terminate_once(root: Path, job: Job, rng: random.Random, tally: Tally) -> None:
    variant = rng.choice("AB")
    before = set(leftovers(root))  # a killed run's, not yet reaped
    proc = start(root, job.args[variant])
    time.sleep(rng.uniform(0.3, 1.0) * tally.durations[job.name, variant])
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate()
    if proc.returncode == 128 + signal.SIGTERM:
        if "error: interrupted by SIGTERM" not in err or "Traceback" in err:
            tally.fail(f"{job.name}: SIGTERM message: {err.strip()[-300:]}")
        tally.outcomes["SIGTERM: interrupted"] += 1
    else:
        tally.outcomes[f"SIGTERM: exit {proc.returncode}"] += 1
    if set(leftovers(root)) - before:
        tally.fail(f"{job.name}: SIGTERM left {sorted(set(leftovers(root)) - before)}")
    classify(root, job, tally)


def campaign(
    root: Path,
    *,
    kills: int,
    pairs: int,
    terms: int,
    seed: int,
    names: list[str] | None = None,
    repeat: bool = True,
) -> Tally:
    """Prepare ``root``, record the references, then kill, race and terminate runs.

    ``names`` selects jobs (default all); ``repeat`` runs variant A twice at the start, to
    check that a run is reproducible (the comparison with the references relies on it).
    """
    rng = random.Random(seed)
    chosen = [job for job in jobs() if names is None or job.name in names]
    prepare(root, {job.needs for job in chosen})
    tally = Tally()
    for job in chosen:
        for variant in "AB":
            complete_run(root, job, variant, tally)
        if repeat:
            complete_run(root, job, "A", tally)  # same arguments, same output
    for _ in range(kills):
        kill_once(root, rng.choice(chosen), rng, tally)
    for _ in range(pairs):
        concurrent_pair(root, rng.choice(chosen), rng, tally)
    for _ in range(terms):
        terminate_once(root, rng.choice(chosen), rng, tally)
    for job in chosen:  # the next runs reap what the killed ones left
        complete_run(root, job, "B", tally)
    if leftovers(root):
        tally.fail(f"temporaries or locks outlived the runs: {leftovers(root)}")
    return tally


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--kills", type=int, default=60)
    parser.add_argument("--pairs", type=int, default=6)
    parser.add_argument("--terms", type=int, default=6)
    parser.add_argument("--seed", type=int, default=0)
    options = parser.parse_args()
    began = time.monotonic()
    with tempfile.TemporaryDirectory() as root:
        tally = campaign(
            Path(root),
            kills=options.kills,
            pairs=options.pairs,
            terms=options.terms,
            seed=options.seed,
        )
    print(f"{options.kills} SIGKILLs, {options.pairs} concurrent pairs, {options.terms} SIGTERMs "
          f"over {len(jobs())} jobs in {time.monotonic() - began:.0f} s")  # fmt: skip
    for key, seconds in sorted(tally.durations.items()):
        print(f"  {key[0]} {key[1]}: {seconds:.1f} s uninterrupted")
    for outcome, count in sorted(tally.outcomes.items()):
        print(f"  {outcome}: {count}")
    print(
        f"  temporaries or locks seen right after a kill (reaped later): {tally.stale_after_kill}"
    )
    print(f"  failures: {len(tally.failures)}")
    sys.exit(1 if tally.failures else 0)


if __name__ == "__main__":
    main()
