"""A power stage the bridge runs (rm_robot alone): what goes out on /power_limit."""

import logging
import math

from rm_base.control import ChassisPowerModel
from rm_base.plugin.joints import JointStateView
from rm_base.plugin.remote_power import RemotePowerStage

MODEL = ChassisPowerModel(2.96, 3.08e-3, 2.8)


def stage():
    sent = []

    class Publisher:
        publish = sent.append

    return RemotePowerStage(Publisher(), 'chassis', ('fl', 'fr'), MODEL,
                            JointStateView(logging.getLogger('test'))), sent


def test_the_model_goes_out_at_once_and_again_when_it_changes_with_the_limit_kept():
    power, sent = stage()
    assert (sent[-1].k1, sent[-1].limit_w) == (2.96, math.inf)
    power.limit_w = 80.0
    power.model = ChassisPowerModel(3.5, 1e-3, 4.0)
    assert len(sent) == 3
    last = sent[-1]
    assert (last.group, list(last.joints)) == ('chassis', ['fl', 'fr'])
    assert (last.k1, last.k2, last.static_power_w, last.limit_w) == (3.5, 1e-3, 4.0, 80.0)
    assert power.model == ChassisPowerModel(3.5, 1e-3, 4.0)
