"""LK-TECH (LingKong) MF/MG motors: torque, speed and position commands on 0x140 + id.

``protocol`` (bytes <-> values), ``actuator`` (the joint types), ``sim_device`` (the
simulated motor), ``family`` (the registry record).
"""
