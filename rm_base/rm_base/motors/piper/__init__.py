"""AgileX Piper arm joints driven by per-joint MIT frames (no simulated model).

``protocol`` (bytes <-> values), ``actuator`` (the joint type), ``family`` (the registry
record).
"""
