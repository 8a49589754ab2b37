from lyapcheck.cli import main

main()
