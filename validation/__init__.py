"""Validation of anklelab against variation (not shipped with the package).

- :mod:`validation.cleanroom`: a second session generator written from the papers and the
  design notes alone, without reading the twin's code;
- :mod:`validation.accuracy`: the walking analysis' error distributions over many sessions of
  either generator.
"""
