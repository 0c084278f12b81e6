/* Stand-in for the macOS SDK's header, which a Linux host lacks: ring's C
 * includes it only to tell macOS from iOS. Used by scripts/cc-apple.sh when
 * `cargo check --target *-apple-darwin` runs on Linux; never on a Mac. */
#define TARGET_OS_MAC 1
#define TARGET_OS_OSX 1
#define TARGET_OS_IPHONE 0
