"""Bag-replay tests: scenario bags played into the simulated robot (see harness.py)."""
