"""The referee system on the robot (``rm_plugins/Referee``): its serial link as rm_msgs."""

from rm_plugins.referee.messages import TOPICS
from rm_plugins.referee.plugin import Referee

__all__ = ['TOPICS', 'Referee']
