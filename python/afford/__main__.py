"""python3 -m afford COMMAND ...: the package's commands (`afford tune` runs `python3 -m afford tune`)."""
import sys

COMMANDS = {"tune": "a study over config keys with Optuna (python3 -m afford tune --help)"}


def main(argv: list[str]) -> int:
    if not argv or argv[0] not in COMMANDS:
        print("usage: python3 -m afford COMMAND ...\n" + "\n".join(f"  {c}: {h}" for c, h in COMMANDS.items()),
              file=sys.stderr)
        return 2
    from .tune_command import main as tune
    return tune(argv[1:])


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
