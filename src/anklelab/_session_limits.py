"""The largest Perturberator sessions simulated on request (``simulate``, studies, ``design``):
beyond them one session outgrows a laptop's memory (100 000 trials per point took 24 GB before
the operating system ended the worker)."""

MAX_TRIALS_PER_POINT = 1000
MAX_UNPERTURBED = 4000
