"""Set-up of each worker process of a study's local Dask cluster (a Dask preload module)."""

from __future__ import annotations

import logging
import signal
from typing import Any


def dask_setup(worker: Any) -> None:
    """Ctrl-C is the command's, which ends the cluster: a worker ignores it, instead of printing
    a ``KeyboardInterrupt`` traceback, and keeps its own log quiet. What goes wrong in a
    session is recorded with the session (its error, or that its worker died); what a worker
    logs is the cluster's own business, such as losing the scheduler while the command ends it
    (a heartbeat's traceback, printed after the command's last line).

    Parameters
    ----------
    worker : distributed.Worker
        The worker starting (Dask calls this in its process; nothing of it is used).
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    logging.getLogger("distributed").setLevel(logging.CRITICAL)
