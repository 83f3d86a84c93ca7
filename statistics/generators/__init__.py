"""Generators of synthetic fleet measurements with known hidden effects.

They exist to test the discrepancy finder on data it did not generate:

- ``fleet_twin`` (+ ``twin_effects``): the hybrid-model twin the finder was first built on;
- ``fleet_twin_alt``: an independent layout, scatter and effect injection;
- ``fleet_twin_loop``: the twin's layout with the physics wear loop as its truth;
- ``depot``: a depot's measurement campaign written from the physical description of every
  effect (calendar days, heavy-tailed heteroscedastic noise, random effects, dropped and
  repeated measurements, reprofiling mid-series, route changes, mixed instruments);
- ``scenarios``: each generator's fleet with the model a user would calibrate on it, and
  vehicle series measured from a whole-vehicle loop run, shared by the tests and benchmarks.

None of them imports the finder's causes: each effect is written from its physical
description.
"""
