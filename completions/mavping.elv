
use builtin;
use str;

set edit:completion:arg-completer[mavping] = {|@words|
    fn spaces {|n|
        builtin:repeat $n ' ' | str:join ''
    }
    fn cand {|text desc|
        edit:complex-candidate $text &display=$text' '(spaces (- 14 (wcswidth $text)))$desc
    }
    var command = 'mavping'
    for word $words[1..-1] {
        if (str:has-prefix $word '-') {
            break
        }
        set command = $command';'$word
    }
    var completions = [
        &'mavping'= {
            cand -c 'Stop after sending COUNT requests (and waiting for their replies)'
            cand --count 'Stop after sending COUNT requests (and waiting for their replies)'
            cand -i 'Time between requests, e.g. 1s, 100ms, 0.01'
            cand --interval 'Time between requests, e.g. 1s, 100ms, 0.01'
            cand --rate 'Requests per second (instead of --interval)'
            cand -w 'Stop after this long, whatever is still in flight'
            cand --deadline 'Stop after this long, whatever is still in flight'
            cand -W 'How long to wait for each reply before counting it lost'
            cand --timeout 'How long to wait for each reply before counting it lost'
            cand --sysid 'Our MAVLink system id (the header of our requests)'
            cand --compid 'Our MAVLink component id'
            cand --mavlink 'MAVLink version of our requests (replies of either version are accepted)'
            cand --first-seq 'Sequence number of the first request (to test wrap-around)'
            cand --format 'Output format'
            cand --max-loss 'Fail (exit 1) when a responder loses more than PCT, e.g. 5% or 0.5'
            cand --max-rtt 'Fail when an RTT figure is above a limit: [p50|p90|p99|p99.9|mean|max=]DURATION (default figure: max); repeatable, e.g. --max-rtt p99=50ms'
            cand --max-jitter 'Fail when a responder''s jitter is above DURATION'
            cand --expect 'A responder that must answer: SYSID or SYSID/COMPID (on every link), or LINK=SYSID[/COMPID] (on that one of several links); repeatable'
            cand --min-responders 'Fail unless at least N responders answer'
            cand --hgrm 'Write each responder''s RTT distribution in HdrHistogram''s .hgrm format'
            cand --samples 'Write one CSV row per reply or loss (sysid,compid,seq,sent_s,rtt_us,status, then the latest RADIO_STATUS figures)'
            cand --baud 'Baud rate of a serial device whose connection string names none'
            cand --probe 'What to send: ping, timesync (also ArduPilot; measures clock offset), command'
            cand --target 'Address requests to SYS/COMP (timesync: default 0/0, everyone; command: default 1/1)'
            cand --command '--probe command: MAV_CMD name or id, then up to 7 params, comma-separated'
            cand --retry-interval '--probe command: re-send an unacknowledged command this often'
            cand --retries '--probe command: re-sends after the first before a command counts as failed'
            cand --prometheus 'Serve Prometheus metrics at http://ADDR:PORT/metrics while the run goes on'
            cand --plot 'At the end, draw RTT over time and the RTT distribution to FILE.svg'
            cand --signing-key 'MAVLink 2 signing key: 64 hex characters (the 32-byte secret) or a passphrase, hashed with SHA-256 as MAVProxy does. Signs what we send and checks what we receive. Prefer MAVPING_SIGNING_KEY or --signing-key-file: a command line ends up in shell history'
            cand --signing-key-file 'Read the signing key from FILE (its content, trimmed)'
            cand --signing-link-id 'Link id in the signature of our frames (0-255)'
            cand --generate 'Print shell completions or the man page (for packagers)'
            cand -q 'Print only the summary'
            cand --quiet 'Print only the summary'
            cand --every-reply 'Print a line for every reply even above 100 requests/s (where one status line per second is printed instead)'
            cand --no-heartbeat 'Do not send our 1 Hz GCS HEARTBEAT (MAVSDK ignores PINGs from systems it has not heard)'
            cand -v 'More logs on stderr (-v info, -vv debug, -vvv trace); or set MAVPING_LOG'
            cand --verbose 'More logs on stderr (-v info, -vv debug, -vvv trace); or set MAVPING_LOG'
            cand --json 'Same as --format json: newline-delimited JSON events on stdout'
            cand --reconnect 'When a tcp or serial link breaks, reconnect with backoff instead of ending the run; on udpout an ICMP "port unreachable" does not end it (pings sent while down count as lost)'
            cand --live 'Full-screen live view (q or Ctrl-C to stop); plain text when stdout is not a terminal'
            cand --require-signed 'With a signing key: refuse unsigned replies too (wrongly signed and replayed ones are always refused); refused frames are counted, never measured'
            cand -h 'Print help (see more with ''--help'')'
            cand --help 'Print help (see more with ''--help'')'
            cand -V 'Print version'
            cand --version 'Print version'
            cand respond 'Be a well-behaved MAVLink system that answers PING, TIMESYNC and COMMAND_LONG'
            cand serve 'Probe links for Prometheus: /probe?target=LINK on request (the multi-target exporter pattern) and continuous links at /metrics'
            cand help 'Print this message or the help of the given subcommand(s)'
        }
        &'mavping;respond'= {
            cand --sysid 'Our MAVLink system id'
            cand --compid 'Our MAVLink component id'
            cand --delay 'Hold every reply this long (one-way link emulation)'
            cand --jitter 'Extra delay per reply, uniform in [0, jitter]'
            cand --drop 'Drop this share of replies, e.g. 10 or 10%'
            cand --dup 'Send this share of replies twice'
            cand --seed 'Random seed for --jitter, --drop and --dup'
            cand --baud 'Baud rate of a serial device whose connection string names none'
            cand --signing-key 'MAVLink 2 signing key: 64 hex characters (the 32-byte secret) or a passphrase, hashed with SHA-256 as MAVProxy does. Signs what we send and checks what we receive. Prefer MAVPING_SIGNING_KEY or --signing-key-file: a command line ends up in shell history'
            cand --signing-key-file 'Read the signing key from FILE (its content, trimmed)'
            cand --signing-link-id 'Link id in the signature of our frames (0-255)'
            cand --no-ping 'Answer only TIMESYNC and commands, not PING (like ArduPilot)'
            cand -v 'More logs on stderr (-v info, -vv debug)'
            cand --verbose 'More logs on stderr (-v info, -vv debug)'
            cand -h 'Print help'
            cand --help 'Print help'
        }
        &'mavping;serve'= {
            cand --listen 'Where to serve /probe and /metrics: a numeric ADDR:PORT [default: 127.0.0.1:9465, or listen in --config]'
            cand --config 'TOML file with allowed targets, modules, continuous links and max_concurrent; reread on SIGHUP'
            cand --allow 'Let /probe open targets matching PATTERN, e.g. ''udpout:127.0.0.1:*'' (''*'' stands for one part of an address: a port, an octet, a name; ''**'' for anything); repeatable'
            cand --link 'Probe LINK all the time (PING every second) and show it at /metrics; repeatable'
            cand --max-concurrent 'Most /probe requests running at once; more are answered 503 [default: 16, or max_concurrent in --config]'
            cand -v 'More logs on stderr (-v info, -vv debug)'
            cand --verbose 'More logs on stderr (-v info, -vv debug)'
            cand -h 'Print help (see more with ''--help'')'
            cand --help 'Print help (see more with ''--help'')'
        }
        &'mavping;help'= {
            cand respond 'Be a well-behaved MAVLink system that answers PING, TIMESYNC and COMMAND_LONG'
            cand serve 'Probe links for Prometheus: /probe?target=LINK on request (the multi-target exporter pattern) and continuous links at /metrics'
            cand help 'Print this message or the help of the given subcommand(s)'
        }
        &'mavping;help;respond'= {
        }
        &'mavping;help;serve'= {
        }
        &'mavping;help;help'= {
        }
    ]
    $completions[$command]
}
