# SPDX-License-Identifier: MIT
"""strike batch: a manifest of renders on a Dask cluster, a local one, or one shard with no Dask.

    python3 -m strike.batch MANIFEST.jsonl -o DIR [--workers N | --scheduler ADDRESS | --shard K/N]
                            [--cache DIR] [--similar] [--quiet]

(also `strike batch ...` and `strike-batch ...`). The manifest format is in strike/manifest.py and
docs/datasets.md. For each line, DIR gets ID.wav (32-bit float) and, beside it, ID.json: every
parameter, the scene as rendered, the bank cache keys, the Strike version, the seed and timings.

- Atomic: both files are written under DIR/.partial/HOST-PID-ID/ and renamed into DIR, the WAV
  first; ID.json is the mark of a finished render. A killed worker leaves only its .partial
  folder, which the next run on that host removes once its process is gone.
- Re-runs skip every render whose ID.json is there with the same inputs (job_key); an edited
  line is rendered again.
- One bank cache (--cache, default $STRIKE_CACHE_DIR or ~/.cache/strike), shared by every worker:
  content-addressed, and a bank is solved once (a file lock per entry, src/cache/cache_lock.hpp).
  On a cluster give a folder every worker sees.
- Each worker process keeps one strike.Session for its life: the hulls and bank surfaces of the
  dataset's shapes are built once per worker, not once per render (the same bytes).
- Renders run with one BLAS/OpenMP thread (PINNED_ENVIRONMENT): one single-threaded worker per
  core. The bytes do not depend on it: they equal `strike render`'s (docs/determinism.md).
- --workers N (default: this machine's cores) starts a local Dask cluster, one single-threaded
  worker process per core. --scheduler ADDRESS uses a running cluster (workers need the strike
  package installed). --shard K/N renders lines K, K+N, K+2N, ... (K in 1..N) in this process,
  with no Dask: one Slurm array task (examples/python/slurm-batch.sbatch).
Exit code 0 when every render is done, 1 when a line failed (each failure is printed), as the CLI.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import os
import shutil
import socket
import sys
import time
from typing import Any, Optional

_PARTIAL = ".partial"
# Every render of a batch runs its linear algebra on one thread, wherever it runs: a bank solved
# with multi-threaded OpenBLAS/OpenMP differs in its last bits from one solved single-threaded,
# and so does the audio. Pinned, a render's bytes do not depend on the core count of the machine
# (Dask's nanny pins workers the same way by default); it also keeps one render on one core.
PINNED_ENVIRONMENT = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def _paths(out_dir: str, job_id: str) -> tuple:
    return os.path.join(out_dir, job_id + ".wav"), os.path.join(out_dir, job_id + ".json")


def job_key(job, similar: bool = False) -> str:
    """The job's key, told apart when rendered with --similar (other bytes: docs/datasets.md)."""
    return job.key() if not similar else hashlib.sha256((job.key() + " similar").encode()).hexdigest()


def is_done(job, out_dir: str, similar: bool = False) -> bool:
    """ID.json and ID.wav exist, and ID.json was written for these inputs."""
    wav, meta = _paths(out_dir, job.id)
    if not (os.path.isfile(wav) and os.path.isfile(meta)):
        return False
    try:
        with open(meta, encoding="utf-8") as f:
            return json.load(f).get("job_key") == job_key(job, similar)
    except (OSError, ValueError):
        return False


def _write_json(path: str, value: Any) -> None:
    with open(path, "w", encoding="utf-8") as f:
        json.dump(value, f, indent=1, sort_keys=True)
        f.write("\n")
        f.flush()
        os.fsync(f.fileno())


def _sha256(path: str) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def render_job(job, out_dir: str, cache_dir: str, manifest: str = "", similar: bool = False) -> dict:
    """Renders one job into out_dir (skipping it if done). Runs on a worker; returns a summary
    dict: id, status (done, skipped, failed), error, seconds."""
    started = _render(job, out_dir, cache_dir, similar)
    return started if isinstance(started, dict) else _finish(job, *started, out_dir, cache_dir, manifest, similar)


def _session():
    """This process's strike.Session: a worker renders thousands of scenes of the same few shapes,
    and keeps their hulls and bank surfaces between renders (the bytes do not depend on it)."""
    import strike

    global _SESSION
    if _SESSION is None:
        _SESSION = strike.Session()
    return _SESSION


_SESSION = None


def _render(job, out_dir: str, cache_dir: str, similar: bool):
    """A job's render: (result, start time, render seconds), or its summary when skipped or failed."""
    import strike  # on the worker

    start = time.perf_counter()
    if is_done(job, out_dir, similar):
        return {"id": job.id, "status": "skipped", "seconds": 0.0}
    try:
        # One solve at a time: the workers are one per core already, and each forecasts its memory alone.
        result = strike.render(job.scene, rate=job.rate, duration=job.duration, gain=job.gain, cache=cache_dir,
                               base_dir=job.base_dir, similar=similar, session=_session(), solve_threads=1,
                               output=job.output, hrtf=job.hrtf)
    except strike.InputError as e:
        return {"id": job.id, "status": "failed", "error": f"line {job.line} (id {job.id}): {e}",
                "seconds": time.perf_counter() - start}
    return result, start, time.perf_counter() - start


def _finish(job, result, start: float, render_s: float, out_dir: str, cache_dir: str, manifest: str,
            similar: bool) -> dict:
    """Writes a rendered job's ID.wav and then ID.json (atomically, through .partial); returns its
    summary. `start` is the job's perf_counter start, render_s its render's seconds."""
    import strike

    finish_start = time.perf_counter()
    host, pid = socket.gethostname(), os.getpid()
    partial = os.path.join(out_dir, _PARTIAL, f"{host}-{pid}-{job.id}")
    os.makedirs(partial, exist_ok=True)
    try:
        wav, meta = _paths(out_dir, job.id)
        partial_wav = os.path.join(partial, job.id + ".wav")
        result.save(partial_wav, format="float")
        report = result.metadata
        metadata = {
            "id": job.id,
            "manifest": os.path.abspath(manifest) if manifest else None,
            "line": job.line,
            "source": job.source,
            "parameters": job.parameters,
            "seed": job.seed,
            "scene": job.scene,
            "base_dir": job.base_dir,
            "job_key": job_key(job, similar),
            "similar": similar,
            "strike_version": strike.__version__,
            "audio": {"file": job.id + ".wav", "format": "float", "rate": result.rate, "frames": int(result.audio.shape[0]),
                      "output": job.output, "channels": 1 if result.audio.ndim == 1 else int(result.audio.shape[1]),
                      "sha256": _sha256(partial_wav)},
            "banks": report["banks"],
            "cache_dir": os.path.abspath(cache_dir) if cache_dir else None,
            "report": {k: v for k, v in report.items() if k not in ("banks", "seconds", "scene")},
            "timings_s": dict(report["seconds"], render_call=render_s),
            "worker": {"host": host, "pid": pid},
        }
        os.replace(partial_wav, wav)
        # The render and its WAV's writing (not the wait for render_jobs' writer thread).
        metadata["timings_s"]["job"] = render_s + (time.perf_counter() - finish_start)
        partial_meta = os.path.join(partial, job.id + ".json")
        _write_json(partial_meta, metadata)
        os.replace(partial_meta, meta)  # last: the mark of a finished render
        return {"id": job.id, "status": "done", "seconds": time.perf_counter() - start}
    finally:
        shutil.rmtree(partial, ignore_errors=True)


def render_jobs(jobs: list, out_dir: str, cache_dir: str, manifest: str = "", similar: bool = False) -> list:
    """render_job for each of a few jobs, in order: one Dask task for several renders, since a
    task's round trip through the scheduler costs milliseconds. Each job's files are written by
    one writer thread while the next job renders (the render releases the GIL): writing, fsync
    and renames cost a small render ~10 ms, mostly waiting for the disk. Returns when every
    job's files are in place; a job that raised (an OS error, a bug) is reported failed."""
    from concurrent.futures import ThreadPoolExecutor

    def failed(job, e: BaseException) -> dict:
        return {"id": job.id, "status": "failed", "error": f"line {job.line} (id {job.id}): {type(e).__name__}: {e}"}

    pending: list = []
    with ThreadPoolExecutor(max_workers=1) as writer:  # one thread: jobs finish in order
        for job in jobs:
            try:
                started = _render(job, out_dir, cache_dir, similar)
            except Exception as e:
                pending.append(failed(job, e))
                continue
            if isinstance(started, dict):
                pending.append(started)
            else:
                pending.append(writer.submit(_finish, job, *started, out_dir, cache_dir, manifest, similar))
        summaries = []
        for job, item in zip(jobs, pending):
            if isinstance(item, dict):
                summaries.append(item)
                continue
            try:
                summaries.append(item.result())
            except Exception as e:
                summaries.append(failed(job, e))
    return summaries


def task_size(jobs: int, workers: int) -> int:
    """Renders per Dask task: up to 8, and at least 8 tasks per worker so that the last ones
    still spread over every worker (and a killed worker loses little)."""
    return max(1, min(8, jobs // (8 * max(workers, 1))))


def _import_strike() -> None:
    import strike  # noqa: F401  (loads the module, NumPy and the BLAS once, before the clock)


def remove_dead_partials(out_dir: str) -> int:
    """Removes .partial folders left by processes of this host that are gone (killed workers)."""
    root = os.path.join(out_dir, _PARTIAL)
    host, removed = socket.gethostname(), 0
    if not os.path.isdir(root):
        return 0
    for name in os.listdir(root):
        if not name.startswith(host + "-"):
            continue  # another machine's: only it can tell whether its process is gone
        rest = name[len(host) + 1:]
        pid_text = rest.split("-", 1)[0]
        if not pid_text.isdigit():
            continue
        try:
            os.kill(int(pid_text), 0)
            continue  # alive: a render in progress
        except ProcessLookupError:
            pass
        except PermissionError:
            continue  # alive, another user's
        shutil.rmtree(os.path.join(root, name), ignore_errors=True)
        removed += 1
    try:
        os.rmdir(root)  # only when empty
    except OSError:
        pass
    return removed


class Progress:
    """A progress bar on stderr: done/total, renders per second, time left."""

    def __init__(self, total: int, skipped: int, quiet: bool):
        self.total, self.done, self.failed, self.quiet = total, skipped, 0, quiet
        self.counted_from = skipped
        self.start = time.perf_counter()
        self.tty = sys.stderr.isatty()
        self.last_print = 0.0

    def step(self, status: str) -> None:
        self.done += 1
        self.failed += status == "failed"
        now = time.perf_counter()
        if self.quiet or (now - self.last_print < (0.1 if self.tty else 2.0) and self.done < self.total):
            return
        self.last_print = now
        elapsed = now - self.start
        rate = (self.done - self.counted_from) / elapsed if elapsed > 0 else 0.0
        left = (self.total - self.done) / rate if rate > 0 else float("inf")
        width = 30
        filled = int(width * self.done / max(self.total, 1))
        bar = "#" * filled + "." * (width - filled)
        text = (f"strike batch: [{bar}] {self.done}/{self.total} renders, {rate:.2f}/s, "
                f"{'?' if left == float('inf') else f'{left:.0f} s'} left" + (f", {self.failed} failed" if self.failed else ""))
        sys.stderr.write(("\r" + text) if self.tty else (text + "\n"))
        sys.stderr.flush()

    def finish(self) -> None:
        if self.tty and not self.quiet:
            sys.stderr.write("\n")


def _shard(text: str) -> tuple:
    k, _, n = text.partition("/")
    if not (k.isdigit() and n.isdigit() and 1 <= int(k) <= int(n)):
        raise ValueError(f"--shard = {text} (must be K/N with 1 <= K <= N)")
    return int(k), int(n)


def main(argv: Optional[list] = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if any(os.environ.get(k) != v for k, v in PINNED_ENVIRONMENT.items()):
        # The BLAS reads these when it is loaded (import strike), so start again with them set.
        sys.stdout.flush()
        sys.stderr.flush()
        os.execve(sys.executable, [sys.executable, "-m", "strike.batch", *argv], {**os.environ, **PINNED_ENVIRONMENT})
    parser = argparse.ArgumentParser(prog="strike batch", description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog="Manifest format, randomized scenes and clusters: docs/datasets.md")
    parser.add_argument("manifest", metavar="MANIFEST.jsonl")
    parser.add_argument("-o", dest="out_dir", metavar="DIR", required=True, help="output folder (made if missing)")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, metavar="N", help="local Dask cluster of N worker processes (default: cores)")
    where.add_argument("--scheduler", metavar="ADDRESS", help="use a running Dask cluster, e.g. tcp://head:8786")
    where.add_argument("--shard", metavar="K/N", help="render lines K, K+N, ... here, with no Dask (Slurm arrays)")
    parser.add_argument("--cache", metavar="DIR", help="bank cache folder shared by the workers; default $STRIKE_CACHE_DIR or ~/.cache/strike")
    parser.add_argument("--similar", action="store_true",
                        help="one eigen-solve per shape at unit size, scaled to every size and material (docs/datasets.md)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    args = parser.parse_args(argv)

    import strike
    from .manifest import ManifestError, read_manifest

    def fail(message: str) -> int:
        sys.stderr.write(f"strike batch: {'' if 'error:' in message else 'error: '}{message}\n")
        return 1

    if args.workers is not None and args.workers < 1:
        return fail(f"--workers = {args.workers} (must be >= 1)")
    try:
        jobs = read_manifest(args.manifest)
        shard = _shard(args.shard) if args.shard else None
    except (ManifestError, ValueError) as e:
        return fail(str(e))
    if shard:
        jobs = jobs[shard[0] - 1::shard[1]]
    cache_dir = args.cache if args.cache is not None else strike.default_cache_dir()
    out_dir = os.path.abspath(args.out_dir)
    os.makedirs(out_dir, exist_ok=True)
    remove_dead_partials(out_dir)
    todo = [job for job in jobs if not is_done(job, out_dir, args.similar)]
    progress = Progress(len(jobs), len(jobs) - len(todo), args.quiet)
    failures = []
    start = time.perf_counter()
    startup_s = 0.0

    def record(summary: dict) -> None:
        if summary["status"] == "failed":
            failures.append(summary["error"])
        progress.step(summary["status"])

    if shard or not todo:
        for job in todo:
            record(render_job(job, out_dir, cache_dir, args.manifest, args.similar))
    else:
        from distributed import Client, LocalCluster, as_completed
        cluster = None
        if args.scheduler:
            client = Client(args.scheduler)
        else:
            workers = args.workers or os.cpu_count() or 1
            # One single-threaded process per core: the engine runs one render per thread, and
            # separate processes keep a crashed render from taking the others with it.
            # No dashboard, so no use for each worker's statistical profiler either (a stack sample of
            # every thread each 10 ms): it costs two workers on two cores ~1% of their renders/s.
            import dask

            dask.config.set({"distributed.worker.profile.enabled": False})
            # The cluster's periodic housekeeping, made rarer: an idle 2-worker cluster took 7% of a
            # core (0.2 s in the main process and 0.1 s in each worker per 5 s), now 1.5%. Each is
            # a diagnostic or a safety net that a render of ~40 ms does not need 50 times a
            # second: the event loop's responsiveness check (20 ms -> 0.5 s), the nanny's memory
            # limit check (0.1 -> 1 s), the scheduler's system metrics for a dashboard not started
            # (0.5 -> 2 s), and work stealing (0.1 -> 1 s; tasks wait at the scheduler anyway).
            dask.config.set({"distributed.admin.tick.interval": "500ms", "distributed.worker.memory.monitor-interval": "1s",
                             "distributed.admin.system-monitor.interval": "2s",
                             "distributed.scheduler.work-stealing-interval": "1s"})
            # The workers' environment: the pinned threads, and not Dask's MALLOC_TRIM_THRESHOLD_=65536.
            # Setting it turns off glibc's adaptive mmap threshold, so every large block is mapped
            # and unmapped afresh (page faults per render): it cost a worker's simulation 10-20%,
            # and its renders/s 12% (docs/datasets.md, Throughput). A worker's memory still goes
            # back to the system when it is free for long, as in `strike render`.
            dask.config.set({"distributed.nanny.pre-spawn-environ": dict(PINNED_ENVIRONMENT)})
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
            client = Client(cluster)
        try:
            client.run(_import_strike)  # each worker's start, not its first render's time
            startup_s = time.perf_counter() - start
            progress.start = time.perf_counter()  # the rate counts renders, not the cluster's start
            workers_now = len(client.scheduler_info().get("workers", {})) or 1
            size = task_size(len(todo), workers_now)
            chunks = [todo[k:k + size] for k in range(0, len(todo), size)]
            futures = client.map(render_jobs, chunks, out_dir=out_dir, cache_dir=cache_dir, manifest=args.manifest,
                                 similar=args.similar, pure=False)
            by_future = dict(zip(futures, chunks))
            for future in as_completed(futures):
                try:
                    for summary in future.result():
                        record(summary)
                except Exception as e:  # a worker died more often than Dask retries, or a bug
                    for job in by_future[future]:
                        record({"id": job.id, "status": "failed",
                                "error": f"line {job.line} (id {job.id}): {type(e).__name__}: {e}"})
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    progress.finish()
    try:
        os.rmdir(os.path.join(out_dir, _PARTIAL))  # every render has ended: empty unless a worker died
    except OSError:
        pass
    for failure in failures:
        sys.stderr.write(f"strike batch: error: {failure}\n")
    if not args.quiet:
        rendered = len(todo) - len(failures)
        elapsed = time.perf_counter() - start
        rendering = elapsed - startup_s
        sys.stderr.write(f"strike batch: {rendered} rendered, {len(jobs) - len(todo)} already done, {len(failures)} failed, "
                         f"{elapsed:.1f} s ({rendered / rendering if rendering > 0 else 0:.2f} renders/s"
                         + (f" after {startup_s:.1f} s of cluster start" if startup_s else "") + f") -> {out_dir}\n")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
