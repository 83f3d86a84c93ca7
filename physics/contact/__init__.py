"""Wheel-rail contact: rigid contact geometry (``geometry``), normal and tangential contact.

``geometry`` solves a wheelset's roll and height on its track for given lateral shifts and
reports every contact point with its contact angle, rolling radius and Hertz curvatures; its
module docstring fixes the frames and sign conventions the other contact modules use.
"""
