# Copyright 2026 The formation_ros authors.
# SPDX-License-Identifier: Apache-2.0

"""Process supervision (formation_ros.tools.supervise) with tiny Python child processes."""

import io
import os
import signal
import sys
import textwrap
import time

from formation_ros.tools.supervise import ProcessSpec, Supervisor
import pytest

SLEEPER = 'import time\nprint("ready", flush=True)\ntime.sleep(120)\n'


def child(name, code, *args):
    """Spec of a Python child running ``code`` (dedented) with ``args``."""
    return ProcessSpec(name, [sys.executable, '-c', textwrap.dedent(code), *args])


def wait_until(predicate, timeout=20.0):
    """Check ``predicate`` every 20 ms until it holds or ``timeout`` passes; return its value."""
    deadline = time.monotonic() + timeout
    while not predicate() and time.monotonic() < deadline:
        time.sleep(0.02)
    return predicate()


def alive(pid):
    """Whether process ``pid`` runs (a zombie left to a parent that does not reap is dead)."""
    try:
        with open(f'/proc/{pid}/stat') as stream:
            return stream.read().rsplit(')', 1)[1].split()[0] != 'Z'
    except FileNotFoundError:
        return False


@pytest.fixture
def supervisor(tmp_path):
    """Give the test a supervisor with log files in tmp_path/logs and its echo in a StringIO."""
    echo = io.StringIO()
    with Supervisor(echo=echo, log_dir=str(tmp_path / 'logs')) as group:
        yield group


def test_output_is_prefixed_and_logged(supervisor):
    supervisor.start(child('talker', """
        import sys
        print('one', flush=True)
        print('two', file=sys.stderr, flush=True)
        sys.stdout.write('no newline at the end')
    """))
    info = supervisor.wait('talker', 20)
    assert info is not None and info.returncode == 0
    assert supervisor.log('talker') == 'one\ntwo\nno newline at the end\n'
    supervisor.close()
    echoed = supervisor.echo.getvalue().splitlines()
    assert echoed == ['[talker] one', '[talker] two', '[talker] no newline at the end']


def test_echo_only_and_no_log_files():
    echo = io.StringIO()
    with Supervisor(echo=echo) as group:
        group.start(child('a', 'print("hello")'))
        assert group.wait('a', 20).returncode == 0
        with pytest.raises(ValueError):
            group.log('a')
    assert echo.getvalue() == '[a] hello\n'


def test_first_death_is_reported_with_its_exit_code(supervisor):
    supervisor.start(child('steady', SLEEPER))
    supervisor.start(child('crasher', 'import sys; sys.exit(3)'))
    info = supervisor.wait_exit(20)
    assert info is not None and info.name == 'crasher'
    assert (info.returncode, info.signal_name, info.stopped) == (3, None, False)
    assert info.reason == 'exit code 3'
    assert [e for e in supervisor.exits() if not e.stopped] == [info]
    assert supervisor.running('steady')
    stopped = supervisor.stop(['steady'], timeout=10)
    assert [(s.name, s.stopped) for s in stopped] == [('steady', True)]
    assert [e.name for e in supervisor.exits() if not e.stopped] == ['crasher']
    assert [e.name for e in supervisor.exits()] == ['crasher', 'steady']


def test_first_death_is_reported_with_its_signal(supervisor):
    supervisor.start(child('steady', SLEEPER))
    supervisor.start(child('killed', 'import os, signal; os.kill(os.getpid(), signal.SIGSEGV)'))
    info = supervisor.wait_exit(20)
    assert info is not None and info.name == 'killed'
    assert info.returncode == -signal.SIGSEGV and info.signal_name == 'SIGSEGV'
    assert info.reason == 'signal SIGSEGV' and not info.stopped


def test_sigint_ends_a_process_that_handles_it(supervisor):
    supervisor.start(child('polite', """
        import time
        print('ready', flush=True)
        try:
            time.sleep(120)
        except KeyboardInterrupt:
            print('closing line', flush=True)
    """))
    assert wait_until(lambda: 'ready' in supervisor.log('polite'))
    [info] = supervisor.stop(['polite'], timeout=10)
    assert info.returncode == 0 and info.stopped
    assert supervisor.log('polite').endswith('closing line\n')


def test_a_process_that_ignores_sigint_is_killed_after_the_deadline(supervisor):
    supervisor.start(child('stubborn', """
        import signal, time
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        print('ready', flush=True)
        time.sleep(120)
    """))
    assert wait_until(lambda: 'ready' in supervisor.log('stubborn'))
    started = time.monotonic()
    [info] = supervisor.stop(['stubborn'], timeout=0.5)
    elapsed = time.monotonic() - started
    assert info.returncode == -signal.SIGKILL and info.signal_name == 'SIGKILL'
    assert 0.5 <= elapsed < 5.0, elapsed


GRANDPARENT = """
    import subprocess, sys, time
    grandchild = subprocess.Popen([sys.executable, '-c', sys.argv[1]])
    print(grandchild.pid, flush=True)
    if sys.argv[2] == 'exit':
        sys.exit(0)
    time.sleep(120)
"""
STUBBORN_GRANDCHILD = ('import signal, time\nsignal.signal(signal.SIGINT, signal.SIG_IGN)\n'
                       'time.sleep(120)\n')


@pytest.mark.parametrize('how', ['stopped', 'exit'])
def test_a_process_group_ends_with_its_leader(supervisor, how):
    supervisor.start(child('parent', GRANDPARENT, STUBBORN_GRANDCHILD, how))
    assert wait_until(lambda: supervisor.log('parent').strip().isdigit())
    grandchild = int(supervisor.log('parent'))
    if how == 'stopped':
        [info] = supervisor.stop(['parent'], timeout=10)
        assert info.stopped and info.returncode != 0
    else:
        info = supervisor.wait('parent', 20)
        assert info is not None and info.returncode == 0 and not info.stopped
    assert wait_until(lambda: not alive(grandchild), 5), f'grandchild {grandchild} survived'


def test_stop_all_follows_the_given_order(supervisor, tmp_path):
    record = tmp_path / 'order.txt'
    code = """
        import sys, time
        print('ready', flush=True)
        try:
            time.sleep(120)
        except KeyboardInterrupt:
            with open(sys.argv[1], 'a') as stream:
                stream.write(sys.argv[2] + '\\n')
    """
    for name in ('a', 'b', 'c', 'd'):
        supervisor.start(child(name, code, str(record), name))
    assert wait_until(lambda: all('ready' in supervisor.log(n) for n in 'abcd'))
    supervisor.stop_all([['c'], ['a']], timeout=10)
    lines = record.read_text().split()
    assert lines[:2] == ['c', 'a'] and sorted(lines[2:]) == ['b', 'd']
    assert all(supervisor.exit_info(n).returncode == 0 for n in 'abcd')
    assert supervisor.exit_info('c').at <= supervisor.exit_info('a').at
    assert supervisor.exit_info('a').at <= min(supervisor.exit_info(n).at for n in 'bd')


def test_paths_with_spaces(tmp_path):
    folder = tmp_path / 'a folder with spaces'
    folder.mkdir()
    script = folder / 'my script.py'
    script.write_text('import os, sys\nprint(sys.argv[1], os.getcwd())\n')
    logs = tmp_path / 'log dir'
    with Supervisor(log_dir=str(logs)) as group:
        group.start(ProcessSpec('spaced', [sys.executable, str(script), 'one argument'],
                                cwd=str(folder)))
        assert group.wait('spaced', 20).returncode == 0
        assert group.log('spaced') == f'one argument {folder}\n'
    assert (logs / 'spaced.log').exists()


def test_a_name_runs_once_at_a_time_and_can_be_started_again(supervisor):
    supervisor.start(child('worker', SLEEPER))
    with pytest.raises(ValueError):
        supervisor.start(child('worker', SLEEPER))
    assert wait_until(lambda: 'ready' in supervisor.log('worker'))
    assert supervisor.stop(['worker'], timeout=10)[0].stopped
    supervisor.start(child('worker', 'print("again")'))
    assert supervisor.wait('worker', 20).returncode == 0
    log = supervisor.log('worker')
    assert log.startswith('ready\n') and log.endswith('\nagain\n'), log
    assert supervisor.names() == ['worker']


def test_close_ends_every_process(tmp_path):
    group = Supervisor(log_dir=str(tmp_path))
    pids = [group.start(child(f'p{k}', SLEEPER)).pid for k in range(3)]
    group.close(timeout=5)
    assert not any(alive(pid) for pid in pids)
    assert all(group.exit_info(f'p{k}').stopped for k in range(3))


def test_restart_starts_the_same_spec_again(supervisor):
    supervisor.start(child('worker', 'import sys; print("run", sys.argv[1])', 'x y'))
    assert supervisor.starts('worker') == 1 and supervisor.starts('other') == 0
    first = supervisor.wait('worker', 20)
    assert first is not None and first.returncode == 0 and not first.stopped
    popen = supervisor.restart('worker')
    second = supervisor.wait('worker', 20)
    assert second is not None and second.pid == popen.pid != first.pid
    assert supervisor.starts('worker') == 2
    assert supervisor.log('worker') == 'run x y\nrun x y\n'
    assert [e.name for e in supervisor.exits()] == ['worker', 'worker']


def test_restart_refuses_a_running_process(supervisor):
    supervisor.start(child('worker', SLEEPER))
    with pytest.raises(ValueError):
        supervisor.restart('worker')
    with pytest.raises(KeyError):
        supervisor.restart('never started')


def test_stop_returns_after_the_last_lines(supervisor):
    supervisor.start(child('slow', """
        import time
        print('ready', flush=True)
        try:
            time.sleep(120)
        except KeyboardInterrupt:
            for k in range(50):
                print('closing', k, flush=True)
    """))
    assert wait_until(lambda: 'ready' in supervisor.log('slow'))
    supervisor.stop(['slow'], timeout=10)
    assert supervisor.echo.getvalue().endswith('[slow] closing 49\n')


def test_a_child_has_a_session_of_its_own(supervisor):
    popen = supervisor.start(child('alone', SLEEPER))
    assert os.getsid(popen.pid) == popen.pid != os.getsid(0)
    assert os.getpgid(popen.pid) == popen.pid != os.getpgid(0)
