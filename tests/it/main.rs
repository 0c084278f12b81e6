//! The integration tests, one binary (one link step): real sockets, ptys,
//! third-party MAVLink peers and the mavping binary. Helpers are in
//! `common/`; each file tests one area.

mod common;

mod advice;
mod age;
mod answers;
mod cli;
mod compare;
mod completions;
mod contrib;
mod damaged;
mod deb;
mod diagnosis;
mod docs;
mod endpoints;
mod exporter;
mod field_logs;
mod habits;
mod high_rate;
mod hostile;
mod late_heard;
mod link_node;
mod live;
mod multilink;
mod mutants;
mod options;
mod pair;
mod passive;
mod passive_outputs;
mod passive_peers;
mod passive_prometheus;
mod probes_pymavlink;
mod prometheus_server;
mod properties;
mod radio;
mod real_logs;
mod respond_links;
mod scripting;
mod serial_pty;
mod serve;
mod serve_secure;
mod serve_transfers;
mod signing;
mod sim_paths;
mod sim_soak;
mod stalled;
mod streams;
mod sweep;
mod tcp_pymavlink;
mod tlog;
mod tlog_record;
mod tlog_rtt;
mod udp_bcast_ipv6;
mod udp_pymavlink;
mod views;
