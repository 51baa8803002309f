"""Jobs on a Ray cluster (``--ray ADDRESS``; the package's ``ray`` extra). Each job runs as
one Ray task (one CPU, never retried by Ray: the sweep reports failures and re-runs them
itself) in a temporary folder on the node that runs it; the folder comes back to the driver
as a tar archive and is committed in the sweep's folder like a local job's. So the nodes
need no shared file system, only the ``admittance`` package (and the binary, for
``admittance run`` jobs) and the files a job names, at the same paths."""

from __future__ import annotations

import io
import pathlib
import tarfile
import tempfile

from ._jobs import Job, Outcome, execute

MISSING_RAY = "--ray needs Ray: pip install './crates/python[ray]' (or pip install ray)"


def _task(job: dict, binary: str | None):
    """On the node: the job into a scratch folder; returns its outcome and the folder as tar."""
    with tempfile.TemporaryDirectory(prefix="admittance-sweep-") as scratch:
        dest = pathlib.Path(scratch) / "job"
        try:
            outcome = execute(Job.from_dict(job), dest, binary)
        except Exception as e:  # noqa: BLE001  (reported as the job's failure)
            outcome = Outcome("failed", 0.0, f"{type(e).__name__}: {e}")
        blob = io.BytesIO()
        if outcome.finished:
            with tarfile.open(fileobj=blob, mode="w") as tar:
                for p in sorted(dest.rglob("*")):
                    tar.add(p, arcname=str(p.relative_to(dest)), recursive=False)
        return outcome, blob.getvalue()


def unpack(blob: bytes, dest: pathlib.Path) -> None:
    """A job folder's archive into ``dest`` (paths stay inside it)."""
    with tarfile.open(fileobj=io.BytesIO(blob), mode="r") as tar:
        tar.extractall(dest, filter="data")


def run_on_ray(address: str, jobs: list, binary: str | None):
    """Yields ``(job, outcome, archive)`` as the cluster at ``address`` finishes each job
    (``"local"``: a Ray instance started on this machine for the sweep)."""
    try:
        import ray
    except ImportError as e:
        raise RuntimeError(MISSING_RAY) from e
    ray.init(address=address, include_dashboard=False, log_to_driver=False, ignore_reinit_error=True)
    try:
        task = ray.remote(num_cpus=1, max_retries=0)(_task)
        pending = {task.remote(job.to_dict(), binary): job for job in jobs}
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            job = pending.pop(done[0])
            try:
                outcome, blob = ray.get(done[0])
            except ray.exceptions.RayError as e:
                outcome, blob = Outcome("failed", 0.0, f"ray: {type(e).__name__}: {str(e).splitlines()[0]}"), b""
            yield job, outcome, blob
    finally:
        ray.shutdown()
