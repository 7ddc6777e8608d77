"""Damiao DM motors (DM4310, DM4340, DM8009, DM10010L...): MIT, position-velocity, velocity.

``protocol`` (bytes <-> values), ``actuator`` (the joint types), ``sim_device`` (the
simulated motor), ``family`` (the registry record).
"""
