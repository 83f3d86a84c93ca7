"""Maintenance planning from measured wheels: fleet state, turning depth, lathe plan.

* :mod:`.limits` — a fleet's limits: Sd/Sh/qR, scrap diameter, diameter differences;
* :mod:`.fleet_state` — each wheel's latest state, remaining kilometres to each limit and
  the date it is reached;
* :mod:`.turning` — the radial cut that restores a target profile, the economic target,
  remaining wheel life;
* :mod:`.lathe_plan` — weeks in which each wheelset is turned under a lathe capacity, and
  its cost against fixed-mileage turning.

Pure: no HTTP, SQL or file I/O.
"""
