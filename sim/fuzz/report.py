"""How ``shary fuzz`` prints a campaign: a line per run as it ends, then a table per
invariant, and every violation with the command that runs it again."""

from __future__ import annotations

from typing import Any

from rich.table import Table

from shary.log.terminal import escape

from .campaign import Campaign, Outcome, command
from .invariants import INVARIANTS

__all__ = ["print_campaign", "progress_line"]


def progress_line(out: Any) -> Any:
    """A ``progress`` callback printing one dim line per run (seed, verdict, time)."""
    def told(outcome: Outcome) -> None:
        mark = "[red]✗[/red]" if outcome.violations else "[green]✓[/green]"
        out.print(f"[dim]{mark} seed {outcome.seed:<6} {outcome.verdict or 'no verdict':<10} "
                  f"{outcome.simulated_seconds:6.1f} s in {outcome.wall_seconds:5.1f} s  "
                  f"{escape(outcome.base)}[/dim]")
    return told


def print_campaign(out: Any, result: Campaign) -> None:
    """The campaign's summary, its table per invariant, its violations."""
    document = result.as_dict()
    runs, family = document["runs"], result.family
    verdicts = document["verdicts"]
    last = result.seed + runs - 1
    out.print(f"[bold]shary fuzz {family}[/bold]: {runs} run{'s' * (runs != 1)} (seed "
              f"{result.seed}{f' to {last}' if runs > 1 else ''}): {verdicts['achieved']} "
              f"achieved, {verdicts['failed']} failed, {verdicts['none']} without a verdict; "
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
