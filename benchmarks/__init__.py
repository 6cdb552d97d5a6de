"""anklelab benchmarks: each prints our time next to a straightforward baseline, as a ratio."""
