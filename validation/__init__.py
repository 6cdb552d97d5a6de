"""Validation tools that live beside anklelab, not inside it.

``validation.cleanroom`` is a second, independently written session generator for the
Perturberator experiment: it shares no code with anklelab's digital twin and serves as unseen
data for the walking analysis.
"""
