
using namespace System.Management.Automation
using namespace System.Management.Automation.Language

Register-ArgumentCompleter -Native -CommandName 'mavping' -ScriptBlock {
    param($wordToComplete, $commandAst, $cursorPosition)

    $commandElements = $commandAst.CommandElements
    $command = @(
        'mavping'
        for ($i = 1; $i -lt $commandElements.Count; $i++) {
            $element = $commandElements[$i]
            if ($element -isnot [StringConstantExpressionAst] -or
                $element.StringConstantType -ne [StringConstantType]::BareWord -or
                $element.Value.StartsWith('-') -or
                $element.Value -eq $wordToComplete) {
                break
        }
        $element.Value
    }) -join ';'

    $completions = @(switch ($command) {
        'mavping' {
            [CompletionResult]::new('-c', '-c', [CompletionResultType]::ParameterName, 'Stop after sending COUNT requests (and waiting for their replies)')
            [CompletionResult]::new('--count', '--count', [CompletionResultType]::ParameterName, 'Stop after sending COUNT requests (and waiting for their replies)')
            [CompletionResult]::new('-i', '-i', [CompletionResultType]::ParameterName, 'Time between requests, e.g. 1s, 100ms, 0.01')
            [CompletionResult]::new('--interval', '--interval', [CompletionResultType]::ParameterName, 'Time between requests, e.g. 1s, 100ms, 0.01')
            [CompletionResult]::new('--rate', '--rate', [CompletionResultType]::ParameterName, 'Requests per second (instead of --interval)')
            [CompletionResult]::new('-w', '-w', [CompletionResultType]::ParameterName, 'Stop after this long, whatever is still in flight')
            [CompletionResult]::new('--deadline', '--deadline', [CompletionResultType]::ParameterName, 'Stop after this long, whatever is still in flight')
            [CompletionResult]::new('-W', '-W ', [CompletionResultType]::ParameterName, 'How long to wait for each reply before counting it lost')
            [CompletionResult]::new('--timeout', '--timeout', [CompletionResultType]::ParameterName, 'How long to wait for each reply before counting it lost')
            [CompletionResult]::new('--sysid', '--sysid', [CompletionResultType]::ParameterName, 'Our MAVLink system id (the header of our requests)')
            [CompletionResult]::new('--compid', '--compid', [CompletionResultType]::ParameterName, 'Our MAVLink component id')
            [CompletionResult]::new('--mavlink', '--mavlink', [CompletionResultType]::ParameterName, 'MAVLink version of our requests (replies of either version are accepted)')
            [CompletionResult]::new('--first-seq', '--first-seq', [CompletionResultType]::ParameterName, 'Sequence number of the first request (to test wrap-around)')
            [CompletionResult]::new('--format', '--format', [CompletionResultType]::ParameterName, 'Output format')
            [CompletionResult]::new('--max-loss', '--max-loss', [CompletionResultType]::ParameterName, 'Fail (exit 1) when a responder loses more than PCT, e.g. 5% or 0.5')
            [CompletionResult]::new('--max-rtt', '--max-rtt', [CompletionResultType]::ParameterName, 'Fail when an RTT figure is above a limit: [p50|p90|p99|p99.9|mean|max=]DURATION (default figure: max); repeatable, e.g. --max-rtt p99=50ms')
            [CompletionResult]::new('--max-jitter', '--max-jitter', [CompletionResultType]::ParameterName, 'Fail when a responder''s jitter is above DURATION')
            [CompletionResult]::new('--expect', '--expect', [CompletionResultType]::ParameterName, 'A responder that must answer: SYSID or SYSID/COMPID (on every link), or LINK=SYSID[/COMPID] (on that one of several links); repeatable')
            [CompletionResult]::new('--min-responders', '--min-responders', [CompletionResultType]::ParameterName, 'Fail unless at least N responders answer')
            [CompletionResult]::new('--hgrm', '--hgrm', [CompletionResultType]::ParameterName, 'Write each responder''s RTT distribution in HdrHistogram''s .hgrm format')
            [CompletionResult]::new('--samples', '--samples', [CompletionResultType]::ParameterName, 'Write one CSV row per reply or loss (sysid,compid,seq,sent_s,rtt_us,status, then the latest RADIO_STATUS figures)')
            [CompletionResult]::new('--baud', '--baud', [CompletionResultType]::ParameterName, 'Baud rate of a serial device whose connection string names none')
            [CompletionResult]::new('--probe', '--probe', [CompletionResultType]::ParameterName, 'What to send: ping, timesync (also ArduPilot; measures clock offset), command')
            [CompletionResult]::new('--target', '--target', [CompletionResultType]::ParameterName, 'Address requests to SYS/COMP (timesync: default 0/0, everyone; command: default 1/1)')
            [CompletionResult]::new('--command', '--command', [CompletionResultType]::ParameterName, '--probe command: MAV_CMD name or id, then up to 7 params, comma-separated')
            [CompletionResult]::new('--retry-interval', '--retry-interval', [CompletionResultType]::ParameterName, '--probe command: re-send an unacknowledged command this often')
            [CompletionResult]::new('--retries', '--retries', [CompletionResultType]::ParameterName, '--probe command: re-sends after the first before a command counts as failed')
            [CompletionResult]::new('--prometheus', '--prometheus', [CompletionResultType]::ParameterName, 'Serve Prometheus metrics at http://ADDR:PORT/metrics while the run goes on')
            [CompletionResult]::new('--plot', '--plot', [CompletionResultType]::ParameterName, 'At the end, draw RTT over time and the RTT distribution to FILE.svg')
            [CompletionResult]::new('--signing-key', '--signing-key', [CompletionResultType]::ParameterName, 'MAVLink 2 signing key: 64 hex characters (the 32-byte secret) or a passphrase, hashed with SHA-256 as MAVProxy does. Signs what we send and checks what we receive. Prefer MAVPING_SIGNING_KEY or --signing-key-file: a command line ends up in shell history')
            [CompletionResult]::new('--signing-key-file', '--signing-key-file', [CompletionResultType]::ParameterName, 'Read the signing key from FILE (its content, trimmed)')
            [CompletionResult]::new('--signing-link-id', '--signing-link-id', [CompletionResultType]::ParameterName, 'Link id in the signature of our frames (0-255)')
            [CompletionResult]::new('--generate', '--generate', [CompletionResultType]::ParameterName, 'Print shell completions or the man page (for packagers)')
            [CompletionResult]::new('-q', '-q', [CompletionResultType]::ParameterName, 'Print only the summary')
            [CompletionResult]::new('--quiet', '--quiet', [CompletionResultType]::ParameterName, 'Print only the summary')
            [CompletionResult]::new('--every-reply', '--every-reply', [CompletionResultType]::ParameterName, 'Print a line for every reply even above 100 requests/s (where one status line per second is printed instead)')
            [CompletionResult]::new('--no-heartbeat', '--no-heartbeat', [CompletionResultType]::ParameterName, 'Do not send our 1 Hz GCS HEARTBEAT (MAVSDK ignores PINGs from systems it has not heard)')
            [CompletionResult]::new('-v', '-v', [CompletionResultType]::ParameterName, 'More logs on stderr (-v info, -vv debug, -vvv trace); or set MAVPING_LOG')
            [CompletionResult]::new('--verbose', '--verbose', [CompletionResultType]::ParameterName, 'More logs on stderr (-v info, -vv debug, -vvv trace); or set MAVPING_LOG')
            [CompletionResult]::new('--json', '--json', [CompletionResultType]::ParameterName, 'Same as --format json: newline-delimited JSON events on stdout')
            [CompletionResult]::new('--reconnect', '--reconnect', [CompletionResultType]::ParameterName, 'When a tcp or serial link breaks, reconnect with backoff instead of ending the run; on udpout an ICMP "port unreachable" does not end it (pings sent while down count as lost)')
            [CompletionResult]::new('--live', '--live', [CompletionResultType]::ParameterName, 'Full-screen live view (q or Ctrl-C to stop); plain text when stdout is not a terminal')
            [CompletionResult]::new('--require-signed', '--require-signed', [CompletionResultType]::ParameterName, 'With a signing key: refuse unsigned replies too (wrongly signed and replayed ones are always refused); refused frames are counted, never measured')
            [CompletionResult]::new('-h', '-h', [CompletionResultType]::ParameterName, 'Print help (see more with ''--help'')')
            [CompletionResult]::new('--help', '--help', [CompletionResultType]::ParameterName, 'Print help (see more with ''--help'')')
            [CompletionResult]::new('-V', '-V ', [CompletionResultType]::ParameterName, 'Print version')
            [CompletionResult]::new('--version', '--version', [CompletionResultType]::ParameterName, 'Print version')
            [CompletionResult]::new('respond', 'respond', [CompletionResultType]::ParameterValue, 'Be a well-behaved MAVLink system that answers PING, TIMESYNC and COMMAND_LONG')
            [CompletionResult]::new('serve', 'serve', [CompletionResultType]::ParameterValue, 'Probe links for Prometheus: /probe?target=LINK on request (the multi-target exporter pattern) and continuous links at /metrics')
            [CompletionResult]::new('help', 'help', [CompletionResultType]::ParameterValue, 'Print this message or the help of the given subcommand(s)')
            break
        }
        'mavping;respond' {
            [CompletionResult]::new('--sysid', '--sysid', [CompletionResultType]::ParameterName, 'Our MAVLink system id')
            [CompletionResult]::new('--compid', '--compid', [CompletionResultType]::ParameterName, 'Our MAVLink component id')
            [CompletionResult]::new('--delay', '--delay', [CompletionResultType]::ParameterName, 'Hold every reply this long (one-way link emulation)')
            [CompletionResult]::new('--jitter', '--jitter', [CompletionResultType]::ParameterName, 'Extra delay per reply, uniform in [0, jitter]')
            [CompletionResult]::new('--drop', '--drop', [CompletionResultType]::ParameterName, 'Drop this share of replies, e.g. 10 or 10%')
            [CompletionResult]::new('--dup', '--dup', [CompletionResultType]::ParameterName, 'Send this share of replies twice')
            [CompletionResult]::new('--seed', '--seed', [CompletionResultType]::ParameterName, 'Random seed for --jitter, --drop and --dup')
            [CompletionResult]::new('--baud', '--baud', [CompletionResultType]::ParameterName, 'Baud rate of a serial device whose connection string names none')
            [CompletionResult]::new('--signing-key', '--signing-key', [CompletionResultType]::ParameterName, 'MAVLink 2 signing key: 64 hex characters (the 32-byte secret) or a passphrase, hashed with SHA-256 as MAVProxy does. Signs what we send and checks what we receive. Prefer MAVPING_SIGNING_KEY or --signing-key-file: a command line ends up in shell history')
            [CompletionResult]::new('--signing-key-file', '--signing-key-file', [CompletionResultType]::ParameterName, 'Read the signing key from FILE (its content, trimmed)')
            [CompletionResult]::new('--signing-link-id', '--signing-link-id', [CompletionResultType]::ParameterName, 'Link id in the signature of our frames (0-255)')
            [CompletionResult]::new('--no-ping', '--no-ping', [CompletionResultType]::ParameterName, 'Answer only TIMESYNC and commands, not PING (like ArduPilot)')
            [CompletionResult]::new('-v', '-v', [CompletionResultType]::ParameterName, 'More logs on stderr (-v info, -vv debug)')
            [CompletionResult]::new('--verbose', '--verbose', [CompletionResultType]::ParameterName, 'More logs on stderr (-v info, -vv debug)')
            [CompletionResult]::new('-h', '-h', [CompletionResultType]::ParameterName, 'Print help')
            [CompletionResult]::new('--help', '--help', [CompletionResultType]::ParameterName, 'Print help')
            break
        }
        'mavping;serve' {
            [CompletionResult]::new('--listen', '--listen', [CompletionResultType]::ParameterName, 'Where to serve /probe and /metrics: a numeric ADDR:PORT [default: 127.0.0.1:9465, or listen in --config]')
            [CompletionResult]::new('--config', '--config', [CompletionResultType]::ParameterName, 'TOML file with allowed targets, modules, continuous links and max_concurrent; reread on SIGHUP')
            [CompletionResult]::new('--allow', '--allow', [CompletionResultType]::ParameterName, 'Let /probe open targets matching PATTERN, e.g. ''udpout:127.0.0.1:*'' (''*'' stands for one part of an address: a port, an octet, a name; ''**'' for anything); repeatable')
            [CompletionResult]::new('--link', '--link', [CompletionResultType]::ParameterName, 'Probe LINK all the time (PING every second) and show it at /metrics; repeatable')
            [CompletionResult]::new('--max-concurrent', '--max-concurrent', [CompletionResultType]::ParameterName, 'Most /probe requests running at once; more are answered 503 [default: 16, or max_concurrent in --config]')
            [CompletionResult]::new('-v', '-v', [CompletionResultType]::ParameterName, 'More logs on stderr (-v info, -vv debug)')
            [CompletionResult]::new('--verbose', '--verbose', [CompletionResultType]::ParameterName, 'More logs on stderr (-v info, -vv debug)')
            [CompletionResult]::new('-h', '-h', [CompletionResultType]::ParameterName, 'Print help (see more with ''--help'')')
            [CompletionResult]::new('--help', '--help', [CompletionResultType]::ParameterName, 'Print help (see more with ''--help'')')
            break
        }
        'mavping;help' {
            [CompletionResult]::new('respond', 'respond', [CompletionResultType]::ParameterValue, 'Be a well-behaved MAVLink system that answers PING, TIMESYNC and COMMAND_LONG')
            [CompletionResult]::new('serve', 'serve', [CompletionResultType]::ParameterValue, 'Probe links for Prometheus: /probe?target=LINK on request (the multi-target exporter pattern) and continuous links at /metrics')
            [CompletionResult]::new('help', 'help', [CompletionResultType]::ParameterValue, 'Print this message or the help of the given subcommand(s)')
            break
        }
        'mavping;help;respond' {
            break
        }
        'mavping;help;serve' {
            break
        }
        'mavping;help;help' {
            break
        }
    })

    $completions.Where{ $_.CompletionText -like "$wordToComplete*" } |
        Sort-Object -Property ListItemText
}
