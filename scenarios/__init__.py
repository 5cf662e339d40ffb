"""Scenarios: ground-motion sources, the scenario catalogue, campaigns and the runner."""
