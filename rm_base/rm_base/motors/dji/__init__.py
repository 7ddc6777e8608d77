"""DJI C620/C610 ESCs (M3508, M2006) and the GM6020: grouped command frames, 1 kHz feedback.

``protocol`` (bytes <-> values), ``actuator`` (the joint types), ``groups`` (the shared
command frames), ``sim_device`` (the simulated ESC), ``family`` (the registry record).
"""
