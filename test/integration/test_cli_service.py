"""rmcli service call in a child process against a test node's service (private domain)."""

import sys

import pytest
from std_srvs.srv import SetBool
from support.ros import start_process, wait_until

pytestmark = pytest.mark.ros

TIMEOUT_S = 30.0  # discovery is ~0.4 s on a quiet machine; far more under CPU steal


def rmcli(*args):
    return start_process([sys.executable, '-m', 'rm_bringup.cli', 'service', *args])


def test_call_sends_the_request_and_prints_the_response(test_node):
    node, executor = test_node
    requests = []

    def handle(request, response):
        requests.append(request.data)
        response.success, response.message = True, f'switched {request.data}'
        return response

    node.create_service(SetBool, '/cli_test/switch', handle)
    proc = rmcli('call', '--timeout', str(TIMEOUT_S), '/cli_test/switch', 'std_srvs/srv/SetBool',
                 '{data: true}')
    try:
        wait_until(lambda: proc.poll() is not None, TIMEOUT_S, spin=executor.spin_once)
    finally:
        out, err = proc.communicate(timeout=TIMEOUT_S)
    assert proc.returncode == 0, err
    assert requests == [True]
    assert "response:\nstd_srvs.srv.SetBool_Response(success=True, message='switched True')" in out


@pytest.mark.parametrize(
    ('args', 'code', 'message'),
    [
        (['/nobody/here', 'std_srvs/srv/Trigger', '--timeout', '0.5'], 1,
         "service '/nobody/here' is not available (0.5 s)"),
        (['/x', 'std_srvs/srv/Trigge'], 1, "unknown service type 'std_srvs/srv/Trigge'"),
        (['/x', 'std_srvs/srv/SetBool', '{dta: true}'], 1, 'dta'),
    ],
    ids=['absent', 'bad-type', 'bad-field'],
)
def test_call_errors_are_one_line(args, code, message):
    proc = rmcli('call', *args)
    out, err = proc.communicate(timeout=TIMEOUT_S)
    assert proc.returncode == code and message in err, f'{out}\n{err}'
