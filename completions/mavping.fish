complete --keep-order --exclusive --command mavping --arguments "(COMPLETE=fish mavping -- (commandline --current-process --tokenize --cut-at-cursor) (commandline --current-token))"
