"""Wheel-rail contact: rigid contact geometry (``geometry``), normal and tangential contact.

``geometry`` solves a wheelset's roll and height on its track for given lateral shifts and
reports every contact point with its contact angle, rolling radius and Hertz curvatures; its
module docstring fixes the frames and sign conventions the other contact modules use.
``locus.wheel_locus`` (roll solved or prescribed) feeds the non-Hertzian chain:
``patches`` (patches merged or split by the interpenetration region, as CONTACT),
``patch_plane`` (a patch's planar problem and grid), ``normal_contact`` (per-wheel normal
contact: BEM ``normal_bem``, coarse BEM, Kik-Piotrowski ``kik_piotrowski``, Hertz; the
function for the curving model is ``normal_contact.wheel_normal_contact``) and
``wheel_rail`` (creepages and FASTSIM on top: ``loaded_wheel_contact``).
"""
