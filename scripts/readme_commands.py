"""Print the README's commands table from the `bsp` argument parsers (every subcommand, action and option).

python scripts/readme_commands.py        # paste between the README's "commands table" markers
"""

from __future__ import annotations

import argparse
from collections.abc import Iterator

PIPE = "\\|"  # a | inside a markdown table cell


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def _option_text(action: argparse.Action) -> str:
    name = action.option_strings[0]
    if action.nargs == 0:
        return f"`{name}`"
    if action.choices is not None:
        choices = PIPE.join(str(c) for c in action.choices)
        return f"`{name} {choices}`"
    metavar = action.metavar if action.metavar is not None else action.dest.upper()
    if isinstance(metavar, tuple):
        metavar = " ".join(metavar)
    if isinstance(action.nargs, int) and action.nargs > 1 and " " not in metavar:
        metavar = " ".join([metavar] * action.nargs)
    if action.nargs in ("+", "*"):
        metavar = f"{metavar}..."
    return f"`{name} {metavar}`"


def _positional_text(action: argparse.Action) -> str:
    name = str(action.metavar or action.dest).upper() if action.metavar is None else str(action.metavar)
    if action.nargs == "?":
        return f"[{name}]"
    if action.nargs in ("+", "*"):
        return f"{name}..."
    return name


def _help(parser: argparse.ArgumentParser, fallback: str | None) -> str:
    return " ".join((fallback or parser.description or "").split()).replace("|", "\\|")


def command_rows(parser: argparse.ArgumentParser) -> Iterator[tuple[str, list[str], str]]:
    """(command with its positionals, option texts, one-line help) per subcommand and per sessions-like action."""
    helps: dict[str, str | None] = {}
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {choice.dest: choice.help for choice in action._choices_actions}
    for name, sub in _subparsers(parser).items():
        actions = _subparsers(sub)
        for action_name, action_parser in actions.items() or {None: sub}.items():
            target = action_parser
            words = [sub.prog if action_name is None else f"{sub.prog} {action_name}"]
            words += [
                _positional_text(a)
                for a in target._actions
                if not a.option_strings and a.nargs != 0 and not isinstance(a, argparse._SubParsersAction)
            ]
            options = [_option_text(a) for a in target._actions if a.option_strings and a.dest != "help"]
            help_text = helps.get(name) if action_name is None else _action_help(sub, action_name)
            yield " ".join(words).replace("|", PIPE), options, _help(target, help_text)


def _action_help(parser: argparse.ArgumentParser, name: str) -> str | None:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for choice in action._choices_actions:
                if choice.dest == name:
                    return choice.help
    return None


def markdown_table(parser: argparse.ArgumentParser) -> str:
    """The commands table: command, its options, what it does."""
    lines = ["| command | options | what it does |", "|---|---|---|"]
    for command, options, help_text in command_rows(parser):
        lines.append(f"| `{command}` | {', '.join(options) or '-'} | {help_text} |")
    return "\n".join(lines)


if __name__ == "__main__":
    from bsp_ros.cli import build_parser

    print(markdown_table(build_parser()))
