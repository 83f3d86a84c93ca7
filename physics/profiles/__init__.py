"""Wheel and rail profiles: analytic standards and measured profiles."""
