"""Motors running the MIT Cheetah firmware: MIT frames, enable / disable / set zero.

``protocol`` (bytes <-> values), ``actuator`` (the joint type), ``sim_device`` (the
simulated motor), ``family`` (the registry record).
"""
