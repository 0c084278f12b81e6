complete -c mavping -s c -l count -d 'Stop after sending COUNT requests (and waiting for their replies)' -r
complete -c mavping -s i -l interval -d 'Time between requests, e.g. 1s, 100ms, 0.01' -r
complete -c mavping -l rate -d 'Requests per second (instead of --interval)' -r
complete -c mavping -s w -l deadline -d 'Stop after this long, whatever is still in flight' -r
complete -c mavping -s W -l timeout -d 'How long to wait for each reply before counting it lost' -r
complete -c mavping -l sysid -d 'Our MAVLink system id (the header of our requests)' -r
complete -c mavping -l compid -d 'Our MAVLink component id' -r
complete -c mavping -l mavlink -d 'MAVLink version of our requests (replies of either version are accepted)' -r
complete -c mavping -l first-seq -d 'Sequence number of the first request (to test wrap-around)' -r
complete -c mavping -l format -d 'Output format' -r -f -a "text\t'Ping-like lines and a summary'
json\t'Newline-delimited JSON events'"
complete -c mavping -l max-loss -d 'Fail (exit 1) when a responder loses more than PCT, e.g. 5% or 0.5' -r
complete -c mavping -l max-rtt -d 'Fail when an RTT figure is above a limit: [p50|p90|p99|p99.9|mean|max=]DURATION (default figure: max); repeatable, e.g. --max-rtt p99=50ms' -r
complete -c mavping -l max-jitter -d 'Fail when a responder\'s jitter is above DURATION' -r
complete -c mavping -l expect -d 'A responder that must answer: SYSID or SYSID/COMPID; repeatable' -r
complete -c mavping -l min-responders -d 'Fail unless at least N responders answer' -r
complete -c mavping -l hgrm -d 'Write each responder\'s RTT distribution in HdrHistogram\'s .hgrm format' -r -F
complete -c mavping -l samples -d 'Write one CSV row per reply or loss (sysid,compid,seq,sent_s,rtt_us,status)' -r -F
complete -c mavping -l baud -d 'Baud rate of a serial device whose connection string names none' -r
complete -c mavping -l generate -d 'Print shell completions or the man page (for packagers)' -r -f -a "complete-bash\t''
complete-zsh\t''
complete-fish\t''
complete-powershell\t''
complete-elvish\t''
man\t''"
complete -c mavping -s q -l quiet -d 'Print only the summary'
complete -c mavping -l no-heartbeat -d 'Do not send our 1 Hz GCS HEARTBEAT (MAVSDK ignores PINGs from systems it has not heard)'
complete -c mavping -s v -l verbose -d 'More logs on stderr (-v info, -vv debug, -vvv trace); or set MAVPING_LOG'
complete -c mavping -l json -d 'Same as --format json: newline-delimited JSON events on stdout'
complete -c mavping -l reconnect -d 'When a tcp or serial link breaks, reconnect with backoff instead of ending the run (pings sent while down count as lost)'
complete -c mavping -s h -l help -d 'Print help (see more with \'--help\')'
complete -c mavping -s V -l version -d 'Print version'
