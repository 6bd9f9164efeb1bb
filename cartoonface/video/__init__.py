"""Driving the cartoon from a video of a talking person (seed 003)."""
