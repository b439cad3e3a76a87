# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""The plant's status (core/rules/plant_status.py): diagnostics values and level, command notes."""

from formation_ros.core.maths.law import make_law
from formation_ros.core.maths.reference import Reference
from formation_ros.core.model.plant import Commands, CommandStatus, PlantModel
from formation_ros.core.rules.admission import Reason, Refusals
from formation_ros.core.rules.lockstep import WAITED, WAITING_FOR
from formation_ros.core.rules.plant_gate import Phase
from formation_ros.core.rules.plant_intake import TEAM
from formation_ros.core.rules.plant_status import CommandWatch, Heard, PlantStatus, robots_named
import numpy as np

LAW = make_law(2.0, 1.0, 'arctan', 'poly', 2, 0.5)
MS = 10_000_000
APPLIED, STALE, FUTURE = CommandStatus.APPLIED, CommandStatus.STALE, CommandStatus.FUTURE


def model():
    start = np.array([[0.0, 0.0], [3.0, 0.0], [0.0, 3.0]])
    return PlantModel(start, np.full(3, 1.0), MS, LAW, Reference('fixed', 2), 50 * MS, 1e-3)


def status(team=False, lockstep=False):
    return PlantStatus(lockstep, False, team, 100.0, 1, LAW.u_bound, now=0.0)


def test_the_level_follows_the_start_up_then_lost_robots_then_the_rate():
    plant = model()
    alive = Heard(['alive'] * 3)
    report = status()
    assert report.report(1.0, plant, Phase.LOOKING, 'running', 0, Refusals(), alive)[:2] == (
        'ok', 'looking for another plant on this domain')
    assert report.report(2.0, plant, Phase.WAITING, 'running', 0, Refusals(), alive)[:2] == (
        'ok', 'waiting for the robots')
    level, message, values = report.report(3.0, plant, Phase.RUNNING, 'running', 0, Refusals(),
                                           Heard(['alive', 'lost', 'unknown']))
    assert (level, message) == ('warn', '1 robots gone (no recent cmd_vel)')
    assert values['robots with alive cmd_vel'] == '1'
    assert values['robots with lost cmd_vel'] == '2'
    commands = Commands.empty(3, 2)
    for _ in range(85):
        commands.store_all(np.zeros((3, 2)), plant.t_ns)
        plant.advance(commands)
    level, message, values = report.report(4.0, plant, Phase.RUNNING, 'running', 0, Refusals(),
                                           alive)
    assert (level, message) == ('warn', 'stepping at 85.0 Hz of 100.0 Hz')
    assert values['step rate achieved [Hz]'] == 85.0 and values['steps'] == 85
    report.restart(4.0, plant.counts.steps)
    assert status(lockstep=True).report(5.0, plant, Phase.RUNNING, 'running', 0, Refusals(),
                                        alive)[:2] == ('ok', 'running')
    waiting = Heard(['alive', 'lost', 'alive'],
                    waiting={WAITING_FOR: '2', WAITED: 2.31})
    level, message, values = status(lockstep=True).report(6.0, plant, Phase.RUNNING, 'running',
                                                          0, Refusals(), waiting)
    assert (level, message) == ('warn', 'lockstep: waiting for robots 2 for 2.3 s')
    assert values[WAITING_FOR] == '2' and values[WAITED] == 2.31


def test_errors_come_first_and_name_what_was_heard():
    plant = model()
    heard = Heard(['alive'] * 3, shared={'/clock': '/plant on host b'}, plants='/plant on b',
                  disagreeing=['/reference: num_robots 4 (here: 3)'])
    level, message, values = status().report(1.0, plant, Phase.WAITING, 'running', 0,
                                             Refusals(), heard)
    assert level == 'error'
    assert message == ('0 collisions, 0 commands above the bound, 1 topics with several '
                       'publishers, 0 robots in several processes, 1 nodes with other team '
                       'values')
    assert values['topics with more than one publisher'] == '/clock: /plant on host b'
    assert values['other plants'] == '/plant on b'


def test_refusals_show_under_the_keys_of_before():
    refusals = Refusals()
    for source, reason in [(1, Reason.FRAME), (1, Reason.FRAME), (0, Reason.MALFORMED),
                           (TEAM, Reason.MALFORMED), (TEAM, Reason.FRAME),
                           ('shape', Reason.CHANGE)]:
        refusals.add(source, reason)
    listened = np.array([True, False, True])
    values = status(team=True).report(1.0, model(), Phase.RUNNING, 'stopped', 7, refusals,
                                      Heard(['alive'] * 3, 2, listened))[2]
    assert values['robots with cmd_vel in a frame other than their command frame'] == '2: 2'
    assert values['robots with malformed cmd_vel messages'] == '1: 1'
    assert values['refused shape messages'] == 1
    assert values['malformed team command messages'] == 1
    assert values['team command messages in another frame'] == 1
    assert values['team command publishers'] == 2
    assert values['robots with pose and neighbors published'] == '1, 3'
    assert values['team'] == 'stopped' and values['held steps'] == 7
    plain = status().report(1.0, model(), Phase.RUNNING, 'running', 0, Refusals(),
                            Heard(['alive'] * 3))[2]
    assert 'transport' not in plain
    assert 'robots with malformed cmd_vel messages' not in plain


def test_robots_whose_commands_go_stale_in_one_step_share_one_line():
    watch = CommandWatch(4)
    stamps = np.array([0, 0, 0, 0], dtype=np.int64)
    notes = watch.update(np.array([STALE, STALE, APPLIED, FUTURE], np.int8), stamps, 300 * MS)
    starts = [note for note in notes if note.starts]
    assert starts[0].keys == ('stale-0', 'stale-1')
    assert starts[0].line(['stale-0', 'stale-1']) == (
        'robots 1 and 2: latest commands 3 s old at most; using zero')
    assert starts[0].line(['stale-1']) == 'robot 2: latest command 3 s old; using zero'
    assert [note.keys for note in starts[1:]] == [('future-3',)]
    assert watch.update(np.array([STALE, STALE, APPLIED, FUTURE], np.int8), stamps, 0) == []
    notes = watch.update(np.array([APPLIED, STALE, APPLIED, APPLIED], np.int8), stamps, 0)
    ends = [note for note in notes if not note.starts]
    assert ends[0].keys == ('stale-0', 'stale-3')
    assert ends[0].line(['stale-0']) == 'robot 1: commands fresh again'
    assert ('future-3',) in [note.keys for note in ends]
    assert watch.command_status.tolist() == [APPLIED, STALE, APPLIED, APPLIED]


def test_robots_named():
    assert robots_named([3]) == 'robot 4'
    assert robots_named([6, 0, 3]) == 'robots 1, 4 and 7'
    assert robots_named(range(100)) == 'robots 1, 2, 3, 4, 5 and 95 more'
