"""Helpers for the simulator tests."""

import uuid

import can


def unique_channel(prefix: str = 'simtest') -> str:
    """A channel name no other test (or parallel run) uses."""
    return f'{prefix}-{uuid.uuid4().hex[:10]}'


def drain(bus: can.BusABC) -> list[can.Message]:
    """Every frame waiting in the bus's receive queue (stepped mode: nothing is in flight)."""
    frames = []
    while (msg := bus.recv(timeout=0)) is not None:
        frames.append(msg)
    return frames


def send(bus: can.BusABC, can_id: int, data: bytes) -> None:
    bus.send(can.Message(arbitration_id=can_id, data=data, is_extended_id=False))
