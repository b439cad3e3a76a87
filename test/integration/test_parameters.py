# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""What `ros2 param list/get/dump` would see: every declared parameter answers with a value."""

from formation_ros.core.settings.declarations import Exe, used_by
from formation_ros.core.settings.params_file import load_params_file
from helpers import node, SQUARE
from rcl_interfaces.msg import ParameterType
from rcl_interfaces.srv import GetParameters, ListParameters

NODES = {'/plant': Exe.PLANT, '/reference': Exe.REFERENCE, '/robot_2/robot': Exe.ROBOT,
         '/record': Exe.RECORD}
SERVICE_WAIT = 60.0


def call(probe, client, request):
    """Call a service of a node under test once it is there; return the response."""
    assert probe.spin_until(client.service_is_ready, SERVICE_WAIT), client.srv_name
    future = client.call_async(request)
    assert probe.spin_until(future.done, SERVICE_WAIT), client.srv_name
    return future.result()


def test_every_declared_parameter_comes_back_with_a_value(processes, install, probe, tmp_path):
    processes.start(node(install, 'plant', SQUARE))
    processes.start(node(install, 'reference', SQUARE, '-p', 'use_sim_time:=true'))
    processes.start(node(install, 'robot', SQUARE, '-r', '__ns:=/robot_2', '-p', 'robot_id:=2',
                         process='robot_2'))
    processes.start(node(install, 'record', SQUARE, '-p', f"record.path:={tmp_path / 'bag'}"))
    given = load_params_file(SQUARE)
    for name, exe in NODES.items():
        listed = call(probe, probe.create_client(ListParameters, f'{name}/list_parameters'),
                      ListParameters.Request()).result.names
        answer = call(probe, probe.create_client(GetParameters, f'{name}/get_parameters'),
                      GetParameters.Request(names=listed))
        assert len(answer.values) == len(listed), (name, listed)
        unset = [n for n, v in zip(listed, answer.values)
                 if v.type == ParameterType.PARAMETER_NOT_SET]
        assert not unset, (name, unset)
        expected = {param.name for param in used_by(exe)
                    if param.default is not None or param.name in given}
        expected |= {'reference.origin', 'reference.velocity', 'use_sim_time'}
        assert expected <= set(listed), (name, sorted(expected - set(listed)))
        values = dict(zip(listed, answer.values))
        assert values['num_robots'].integer_value == 4
        assert list(values['reference.origin'].double_array_value) == [0.0, 0.0]
    robot = call(probe, probe.create_client(GetParameters, '/robot_2/robot/get_parameters'),
                 GetParameters.Request(names=['robot_id', 'formation.vertices']))
    assert robot.values[0].integer_value == 2
    assert list(robot.values[1].double_array_value) == given['formation.vertices']
