"""How ``shary fuzz`` prints a campaign: a line per run as it ends, then a table per
invariant, and every violation with the command that runs it again."""

from __future__ import annotations

from typing import Any

from rich.table import Table

from shary.log.terminal import escape

from .campaign import Campaign, Outcome, command
from .invariants import INVARIANTS

__all__ = ["print_campaign", "progress_line"]


_COLUMNS = "seed    task verdict  invariants held  simulated     wall  scenario"
"""The header of the lines :func:`progress_line` prints: whether the run's task ended
well (achieved, failed) and whether the supervisor behaved (its invariants held) are two
columns, since a task that fails by design is no fault of the supervisor's."""


def progress_line(out: Any) -> Any:
    """A ``progress`` callback printing one dim line per run (seed, task verdict,
    invariants held, times, scenario), under :data:`_COLUMNS`, printed with the first."""
    started: list[bool] = []

    def told(outcome: Outcome) -> None:
        if not started:
            started.append(True)
            out.print(f"[dim]{_COLUMNS}[/dim]")
        checked = len(outcome.checked)
        held, colour = ((f"✗ {checked - len(outcome.violations)} of {checked}", "red")
                        if outcome.violations else (f"✓ all {checked}", "green"))
        violated = (f" [red](violated: {escape(', '.join(outcome.violations))})[/red]"
                    if outcome.violations else "")
        out.print(f"[dim]{outcome.seed:<7} {outcome.verdict or 'no verdict':<13} "
                  f"[{colour}]{held:<15}[/{colour}]  {outcome.simulated_seconds:7.1f} s  "
                  f"{outcome.wall_seconds:5.1f} s  {escape(outcome.base)}{violated}[/dim]")
    return told


def print_campaign(out: Any, result: Campaign) -> None:
    """The campaign's summary, its table per invariant, its violations."""
    document = result.as_dict()
    runs, family = document["runs"], result.family
    verdicts = document["verdicts"]
    last = result.seed + runs - 1
    held = sum(not outcome.violations for outcome in result.outcomes)
    out.print(f"[bold]shary fuzz {family}[/bold]: {runs} run{'s' * (runs != 1)} (seed "
              f"{result.seed}{f' to {last}' if runs > 1 else ''}): task verdicts "
              f"{verdicts['achieved']} achieved, {verdicts['failed']} failed, "
              f"{verdicts['none']} none; invariants held in {held} of {runs}; "
              f"{document['simulated_seconds']:g} s simulated in "
              f"{document['wall_seconds']:.1f} s")
    summary = Table(title="invariants", title_justify="left")
    for column, justify in (("invariant", "left"), ("what must hold", "left"),
                            ("checked", "right"), ("held", "right"), ("violated", "right")):
        summary.add_column(column, justify=justify)  # type: ignore[arg-type]
    for invariant, counts in zip(INVARIANTS, document["invariants"], strict=True):
        checked, violated = counts["checked"], counts["violated"]
        if not checked:  # not an invariant of this family
            summary.add_row(f"[dim]{invariant.name}[/dim]",
                            f"[dim]{escape(invariant.says)} (not for {family})[/dim]",
                            "[dim]—[/dim]", "[dim]—[/dim]", "[dim]—[/dim]")
            continue
        summary.add_row(invariant.name, escape(invariant.says), str(checked),
                        str(checked - violated),
                        f"[red]{violated}[/red]" if violated else "[green]0[/green]")
    out.print(summary)
    keys = document["keys"]
    out.print(f"keys drawn: {keys['drawn']}, each run again without it (keys-matter); "
              f"{keys['unreached']} never had their moment (the people did something "
              f"else first)")
    for invariant, counts in zip(INVARIANTS, document["invariants"], strict=True):
        if not counts["violated"]:
            continue
        table = Table(title=f"[bold red]{invariant.name}[/bold red]: {escape(invariant.says)}"
                      f" — violated {counts['violated']} time"
                      f"{'s' * (counts['violated'] != 1)}", title_justify="left")
        table.add_column("seed", justify="right")
        table.add_column("what was seen (the scenario varied)", overflow="fold")
        table.add_column("run it again", no_wrap=True)
        for outcome, name, what in result.violations:
            if name == invariant.name:
                table.add_row(str(outcome.seed), f"{escape(what)} [dim]({outcome.base})[/dim]",
                              command(family, outcome.seed))
        out.print(table)
