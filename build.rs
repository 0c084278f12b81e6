//! One switch for the code: `cfg(mavping_portable)` is the portable path
//! (plain tokio sockets, one datagram a call, user-space receive stamps,
//! tokio's timer plus a short spin), the only code a system other than
//! Linux gets; on Linux the `portable` feature selects it too, so the test
//! suite runs it here (scripts/test.sh). Without it Linux keeps its fast
//! paths (timerfd, recvmmsg/sendmmsg, GSO/GRO, SO_TIMESTAMPNS, -I).
fn main() {
    println!("cargo::rustc-check-cfg=cfg(mavping_portable)");
    println!("cargo::rerun-if-changed=build.rs");
    let linux = std::env::var("CARGO_CFG_TARGET_OS").is_ok_and(|os| os == "linux");
    let asked = std::env::var_os("CARGO_FEATURE_PORTABLE").is_some();
    if !linux || asked {
        println!("cargo::rustc-cfg=mavping_portable");
    }
}
