from groupfit.cli import main

raise SystemExit(main())
