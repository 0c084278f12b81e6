# Print an optspec for argparse to handle cmd's options that are independent of any subcommand.
function __fish_mavping_global_optspecs
    string join \n c/count= i/interval= rate= w/deadline= W/timeout= q/quiet every-reply sysid= compid= mavlink= no-heartbeat first-seq= v/verbose format= json max-loss= max-rtt= max-jitter= expect= min-responders= hgrm= samples= baud= reconnect probe= target= command= retry-interval= retries= live prometheus= plot= signing-key= signing-key-file= signing-link-id= require-signed generate= h/help V/version
end

function __fish_mavping_needs_command
    # Figure out if the current invocation already has a command.
    set -l cmd (commandline -opc)
    set -e cmd[1]
    argparse -s (__fish_mavping_global_optspecs) -- $cmd 2>/dev/null
    or return
    if set -q argv[1]
        # Also print the command, so this can be used to figure out what it is.
        echo $argv[1]
        return 1
    end
    return 0
end

function __fish_mavping_using_subcommand
    set -l cmd (__fish_mavping_needs_command)
    test -z "$cmd"
    and return 1
    contains -- $cmd[1] $argv
end

complete -c mavping -n "__fish_mavping_needs_command" -s c -l count -d 'Stop after sending COUNT requests (and waiting for their replies)' -r
complete -c mavping -n "__fish_mavping_needs_command" -s i -l interval -d 'Time between requests, e.g. 1s, 100ms, 0.01' -r
complete -c mavping -n "__fish_mavping_needs_command" -l rate -d 'Requests per second (instead of --interval)' -r
complete -c mavping -n "__fish_mavping_needs_command" -s w -l deadline -d 'Stop after this long, whatever is still in flight' -r
complete -c mavping -n "__fish_mavping_needs_command" -s W -l timeout -d 'How long to wait for each reply before counting it lost' -r
complete -c mavping -n "__fish_mavping_needs_command" -l sysid -d 'Our MAVLink system id (the header of our requests)' -r
complete -c mavping -n "__fish_mavping_needs_command" -l compid -d 'Our MAVLink component id' -r
complete -c mavping -n "__fish_mavping_needs_command" -l mavlink -d 'MAVLink version of our requests (replies of either version are accepted)' -r
complete -c mavping -n "__fish_mavping_needs_command" -l first-seq -d 'Sequence number of the first request (to test wrap-around)' -r
complete -c mavping -n "__fish_mavping_needs_command" -l format -d 'Output format' -r -f -a "text\t'Ping-like lines and a summary'
json\t'Newline-delimited JSON events'"
complete -c mavping -n "__fish_mavping_needs_command" -l max-loss -d 'Fail (exit 1) when a responder loses more than PCT, e.g. 5% or 0.5' -r
complete -c mavping -n "__fish_mavping_needs_command" -l max-rtt -d 'Fail when an RTT figure is above a limit: [p50|p90|p99|p99.9|mean|max=]DURATION (default figure: max); repeatable, e.g. --max-rtt p99=50ms' -r
complete -c mavping -n "__fish_mavping_needs_command" -l max-jitter -d 'Fail when a responder\'s jitter is above DURATION' -r
complete -c mavping -n "__fish_mavping_needs_command" -l expect -d 'A responder that must answer: SYSID or SYSID/COMPID (on every link), or LINK=SYSID[/COMPID] (on that one of several links); repeatable' -r
complete -c mavping -n "__fish_mavping_needs_command" -l min-responders -d 'Fail unless at least N responders answer' -r
complete -c mavping -n "__fish_mavping_needs_command" -l hgrm -d 'Write each responder\'s RTT distribution in HdrHistogram\'s .hgrm format' -r -F
complete -c mavping -n "__fish_mavping_needs_command" -l samples -d 'Write one CSV row per reply or loss (sysid,compid,seq,sent_s,rtt_us,status, then the latest RADIO_STATUS figures)' -r -F
complete -c mavping -n "__fish_mavping_needs_command" -l baud -d 'Baud rate of a serial device whose connection string names none' -r
complete -c mavping -n "__fish_mavping_needs_command" -l probe -d 'What to send: ping, timesync (also ArduPilot; measures clock offset), command' -r -f -a "ping\t'MAVLink PING (PX4, QGroundControl, MAVSDK answer it)'
timesync\t'TIMESYNC: answered everywhere, ArduPilot included; also measures clock offset'
command\t'COMMAND_LONG re-sent until its COMMAND_ACK arrives'"
complete -c mavping -n "__fish_mavping_needs_command" -l target -d 'Address requests to SYS/COMP (timesync: default 0/0, everyone; command: default 1/1)' -r
complete -c mavping -n "__fish_mavping_needs_command" -l command -d '--probe command: MAV_CMD name or id, then up to 7 params, comma-separated' -r
complete -c mavping -n "__fish_mavping_needs_command" -l retry-interval -d '--probe command: re-send an unacknowledged command this often' -r
complete -c mavping -n "__fish_mavping_needs_command" -l retries -d '--probe command: re-sends after the first before a command counts as failed' -r
complete -c mavping -n "__fish_mavping_needs_command" -l prometheus -d 'Serve Prometheus metrics at http://ADDR:PORT/metrics while the run goes on' -r
complete -c mavping -n "__fish_mavping_needs_command" -l plot -d 'At the end, draw RTT over time and the RTT distribution to FILE.svg' -r -F
complete -c mavping -n "__fish_mavping_needs_command" -l signing-key -d 'MAVLink 2 signing key: 64 hex characters (the 32-byte secret) or a passphrase, hashed with SHA-256 as MAVProxy does. Signs what we send and checks what we receive. Prefer MAVPING_SIGNING_KEY or --signing-key-file: a command line ends up in shell history' -r
complete -c mavping -n "__fish_mavping_needs_command" -l signing-key-file -d 'Read the signing key from FILE (its content, trimmed)' -r -F
complete -c mavping -n "__fish_mavping_needs_command" -l signing-link-id -d 'Link id in the signature of our frames (0-255)' -r
complete -c mavping -n "__fish_mavping_needs_command" -l generate -d 'Print shell completions or the man page (for packagers)' -r -f -a "complete-bash\t''
complete-zsh\t''
complete-fish\t''
complete-powershell\t''
complete-elvish\t''
man\t''"
complete -c mavping -n "__fish_mavping_needs_command" -s q -l quiet -d 'Print only the summary'
complete -c mavping -n "__fish_mavping_needs_command" -l every-reply -d 'Print a line for every reply even above 100 requests/s (where one status line per second is printed instead)'
complete -c mavping -n "__fish_mavping_needs_command" -l no-heartbeat -d 'Do not send our 1 Hz GCS HEARTBEAT (MAVSDK ignores PINGs from systems it has not heard)'
complete -c mavping -n "__fish_mavping_needs_command" -s v -l verbose -d 'More logs on stderr (-v info, -vv debug, -vvv trace); or set MAVPING_LOG'
complete -c mavping -n "__fish_mavping_needs_command" -l json -d 'Same as --format json: newline-delimited JSON events on stdout'
complete -c mavping -n "__fish_mavping_needs_command" -l reconnect -d 'When a tcp or serial link breaks, reconnect with backoff instead of ending the run; on udpout an ICMP "port unreachable" does not end it (pings sent while down count as lost)'
complete -c mavping -n "__fish_mavping_needs_command" -l live -d 'Full-screen live view (q or Ctrl-C to stop); plain text when stdout is not a terminal'
complete -c mavping -n "__fish_mavping_needs_command" -l require-signed -d 'With a signing key: refuse unsigned replies too (wrongly signed and replayed ones are always refused); refused frames are counted, never measured'
complete -c mavping -n "__fish_mavping_needs_command" -s h -l help -d 'Print help (see more with \'--help\')'
complete -c mavping -n "__fish_mavping_needs_command" -s V -l version -d 'Print version'
complete -c mavping -n "__fish_mavping_needs_command" -a "respond" -d 'Be a well-behaved MAVLink system that answers PING, TIMESYNC and COMMAND_LONG'
complete -c mavping -n "__fish_mavping_needs_command" -a "serve" -d 'Probe links for Prometheus: /probe?target=LINK on request (the multi-target exporter pattern) and continuous links at /metrics'
complete -c mavping -n "__fish_mavping_needs_command" -a "help" -d 'Print this message or the help of the given subcommand(s)'
complete -c mavping -n "__fish_mavping_using_subcommand respond" -l sysid -d 'Our MAVLink system id' -r
complete -c mavping -n "__fish_mavping_using_subcommand respond" -l compid -d 'Our MAVLink component id' -r
complete -c mavping -n "__fish_mavping_using_subcommand respond" -l delay -d 'Hold every reply this long (one-way link emulation)' -r
complete -c mavping -n "__fish_mavping_using_subcommand respond" -l jitter -d 'Extra delay per reply, uniform in [0, jitter]' -r
complete -c mavping -n "__fish_mavping_using_subcommand respond" -l drop -d 'Drop this share of replies, e.g. 10 or 10%' -r
complete -c mavping -n "__fish_mavping_using_subcommand respond" -l dup -d 'Send this share of replies twice' -r
complete -c mavping -n "__fish_mavping_using_subcommand respond" -l seed -d 'Random seed for --jitter, --drop and --dup' -r
complete -c mavping -n "__fish_mavping_using_subcommand respond" -l baud -d 'Baud rate of a serial device whose connection string names none' -r
complete -c mavping -n "__fish_mavping_using_subcommand respond" -l signing-key -d 'MAVLink 2 signing key: 64 hex characters (the 32-byte secret) or a passphrase, hashed with SHA-256 as MAVProxy does. Signs what we send and checks what we receive. Prefer MAVPING_SIGNING_KEY or --signing-key-file: a command line ends up in shell history' -r
complete -c mavping -n "__fish_mavping_using_subcommand respond" -l signing-key-file -d 'Read the signing key from FILE (its content, trimmed)' -r -F
complete -c mavping -n "__fish_mavping_using_subcommand respond" -l signing-link-id -d 'Link id in the signature of our frames (0-255)' -r
complete -c mavping -n "__fish_mavping_using_subcommand respond" -l no-ping -d 'Answer only TIMESYNC and commands, not PING (like ArduPilot)'
complete -c mavping -n "__fish_mavping_using_subcommand respond" -s v -l verbose -d 'More logs on stderr (-v info, -vv debug)'
complete -c mavping -n "__fish_mavping_using_subcommand respond" -s h -l help -d 'Print help'
complete -c mavping -n "__fish_mavping_using_subcommand serve" -l listen -d 'Where to serve /probe and /metrics: a numeric ADDR:PORT [default: 127.0.0.1:9465, or listen in --config]' -r
complete -c mavping -n "__fish_mavping_using_subcommand serve" -l config -d 'TOML file with allowed targets, modules, continuous links and max_concurrent; reread on SIGHUP' -r -F
complete -c mavping -n "__fish_mavping_using_subcommand serve" -l allow -d 'Let /probe open targets matching PATTERN, e.g. \'udpout:127.0.0.1:*\' (\'*\' stands for one part of an address: a port, an octet, a name; \'**\' for anything); repeatable' -r
complete -c mavping -n "__fish_mavping_using_subcommand serve" -l link -d 'Probe LINK all the time (PING every second) and show it at /metrics; repeatable' -r
complete -c mavping -n "__fish_mavping_using_subcommand serve" -l max-concurrent -d 'Most /probe requests running at once; more are answered 503 [default: 16, or max_concurrent in --config]' -r
complete -c mavping -n "__fish_mavping_using_subcommand serve" -s v -l verbose -d 'More logs on stderr (-v info, -vv debug)'
complete -c mavping -n "__fish_mavping_using_subcommand serve" -s h -l help -d 'Print help (see more with \'--help\')'
complete -c mavping -n "__fish_mavping_using_subcommand help; and not __fish_seen_subcommand_from respond serve help" -f -a "respond" -d 'Be a well-behaved MAVLink system that answers PING, TIMESYNC and COMMAND_LONG'
complete -c mavping -n "__fish_mavping_using_subcommand help; and not __fish_seen_subcommand_from respond serve help" -f -a "serve" -d 'Probe links for Prometheus: /probe?target=LINK on request (the multi-target exporter pattern) and continuous links at /metrics'
complete -c mavping -n "__fish_mavping_using_subcommand help; and not __fish_seen_subcommand_from respond serve help" -f -a "help" -d 'Print this message or the help of the given subcommand(s)'
