# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""One team: a node started with another parameters file is named by the plant and reference."""

from diagnostic_msgs.msg import DiagnosticStatus
from helpers import logged, node, said_once, Statuses, write_params


def test_a_robot_with_another_file_is_named_by_plant_and_reference(
        processes, install, probe, tmp_path):
    params = write_params(tmp_path, 'square_4.yaml', {})
    other = write_params(tmp_path, 'square_4.yaml', {'controller.gain': 1.0}, name='old.yaml')
    moved = write_params(tmp_path, 'square_4.yaml', {
        'formation.vertices': [1.0, 1.0, -1.0, 1.0, -1.5, -1.5, 1.0, -1.0]}, name='moved.yaml')
    files = {3: moved, 4: other}
    statuses = Statuses(probe)
    processes.start(node(install, 'plant', params))
    processes.start(node(install, 'reference', params, '-p', 'use_sim_time:=true'))
    for i in range(1, 5):
        processes.start(node(install, 'robot', files.get(i, params),
                             '-r', f'__ns:=/robot_{i}', '-p', f'robot_id:={i}',
                             '-p', 'use_sim_time:=true', process=f'robot_{i}'))

    def named(status_name):
        status = statuses.get(status_name)
        if status is None or status.level != DiagnosticStatus.ERROR:
            return ''
        values = {kv.key: kv.value for kv in status.values}
        return values.get('nodes with other team values', '')

    assert probe.spin_until(lambda: 'formation_ros/robot_4' in named('formation_ros/plant')
                            and 'formation_ros/robot_4' in named('formation_ros/reference'), 60)
    # Robot 3 announces its own file's shape until it hears the reference's: wait until it
    # follows it and has said so in two statuses, and plant and reference have spoken since.
    assert probe.spin_until(lambda: "following the reference's shape"
                            in processes.log('robot_3'), 60), processes.log('robot_3')
    for status_name in ('formation_ros/robot_3', 'formation_ros/plant',
                        'formation_ros/reference'):
        after = statuses.heard.get(status_name, 0) + 2
        assert probe.spin_until(lambda: statuses.heard.get(status_name, 0) >= after, 30)
    for status_name in ('formation_ros/plant', 'formation_ros/reference'):
        text = named(status_name)
        assert 'c=1.0' in text and 'c=2.0' in text, text
        assert all(f'formation_ros/robot_{i}' not in text for i in (1, 2, 3)), text
    assert said_once(probe, processes, 'plant', 'formation_ros/robot_4: law', statuses,
                     'formation_ros/plant') == 1, processes.log('plant')
    logged(probe, processes, 'reference', 'formation_ros/robot_4: law')
