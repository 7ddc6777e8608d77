"""The RoboMaster referee system's serial protocol (pure: bytes in, records out).

``frame`` (CRCs, frames, the resyncing parser), ``status`` (the status commands by protocol
version), ``status_encode`` (the same, encoded: the referee's side), ``remote`` (the image
link's ``A9 53`` remote frame), ``client_ui`` (0x0301 and client UI figures).
docs/PROTOCOLS.md §6.
"""

from rm_base.hardware.protocols.referee.client_ui import (
    Color,
    DeleteOp,
    Figure,
    FigureOp,
    FigureType,
    circle,
    client_id,
    delete,
    draw,
    encode_figure,
    interaction,
    line,
    number,
)
from rm_base.hardware.protocols.referee.frame import (
    REMOTE_FRAME_ID,
    FrameParser,
    ParserStats,
    RawFrame,
    crc8,
    crc16,
    decode_frame,
    encode_frame,
)
from rm_base.hardware.protocols.referee.remote import ModeSwitch, RemoteFrame, decode_remote_payload
from rm_base.hardware.protocols.referee.status import (
    LAYOUTS,
    Cmd,
    GameProgress,
    GameStatus,
    Hurt,
    KeyboardMouse,
    PowerHeat,
    ProjectileAllowance,
    ProtocolVersion,
    RobotPosition,
    RobotStatus,
    ShootData,
    StatusDecoder,
)
from rm_base.hardware.protocols.referee.status_encode import encode_status

__all__ = [
    'LAYOUTS',
    'REMOTE_FRAME_ID',
    'Cmd',
    'Color',
    'DeleteOp',
    'Figure',
    'FigureOp',
    'FigureType',
    'FrameParser',
    'GameProgress',
    'GameStatus',
    'Hurt',
    'KeyboardMouse',
    'ModeSwitch',
    'ParserStats',
    'PowerHeat',
    'ProjectileAllowance',
    'ProtocolVersion',
    'RawFrame',
    'RemoteFrame',
    'RobotPosition',
    'RobotStatus',
    'ShootData',
    'StatusDecoder',
    'circle',
    'client_id',
    'crc8',
    'crc16',
    'decode_frame',
    'decode_remote_payload',
    'delete',
    'draw',
    'encode_figure',
    'encode_frame',
    'encode_status',
    'interaction',
    'line',
    'number',
]
