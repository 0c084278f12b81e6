//! The committed completions and man page match the current CLI.
//! Regenerate with `bash scripts/gen-completions.sh`.

#[test]
fn committed_completions_are_current() {
    for (kind, file) in [
        ("complete-bash", "mavping.bash"),
        ("complete-zsh", "_mavping"),
        ("complete-fish", "mavping.fish"),
        ("complete-powershell", "_mavping.ps1"),
        ("complete-elvish", "mavping.elv"),
        ("man", "mavping.1"),
    ] {
        let (code, fresh, err) = crate::common::run_mavping(&["--generate", kind]);
        assert_eq!(code, 0, "{err}");
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("completions")
            .join(file);
        let committed = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            committed == fresh,
            "completions/{file} is out of date: run `bash scripts/gen-completions.sh` and commit"
        );
    }
}
