"""Job process entry point of the local backend: ``python -m lamp.bench.worker JOB OUT``.

``JOB`` is a pickle of ``(job_fn_spec, Job)``; the outcome ``(status, payload, traceback)``
is pickled to ``OUT`` (written to a temporary name, then renamed, so the parent never reads
half a file). A fresh interpreter per job: nothing is inherited from the parent but the
environment, so a job that leaks memory, threads or global state cannot affect the next.
"""

from __future__ import annotations

import os
import pickle
import sys


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print("usage: python -m lamp.bench.worker JOB_PICKLE OUT_PICKLE", file=sys.stderr)
        return 2
    job_path, out_path = argv
    with open(job_path, "rb") as f:
        spec, job = pickle.load(f)
    from lamp.bench.runner import call_job

    outcome = call_job(spec, job)
    tmp = f"{out_path}.tmp"
    with open(tmp, "wb") as f:
        pickle.dump(outcome, f)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, out_path)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
