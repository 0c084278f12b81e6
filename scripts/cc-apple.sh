#!/bin/sh
# The C compiler for the Apple targets (.cargo/config.toml's CC_*_apple_darwin).
# ring (rustls' crypto) compiles C in its build script, which even
# `cargo check` runs. On a Mac: the system compiler and SDK. On Linux, where
# no macOS SDK is installed: clang, freestanding, with ring's own no-libc mode
# and a stand-in for the one SDK header it reads. That is enough to
# type-check; linking a macOS binary needs a Mac (or its SDK) anyway.
if [ "$(uname -s)" = Darwin ]; then
    exec cc "$@"
fi
exec clang -ffreestanding -DRING_CORE_NOSTDLIBINC \
    -isystem "$(dirname "$0")/apple-shim" "$@"
