"""What a simulated CAN device is: its motor's physics, its frames, its faults.

The motor families implement their simulated motors on these (rm_base/motors/*/sim_device.py);
the simulator (rm_base.sim) puts them on channels in a world.
"""
