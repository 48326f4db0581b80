"""sdcompare: convergence / agreement report for one sdcrack results folder."""
