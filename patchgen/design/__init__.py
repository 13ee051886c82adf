"""The controller design: LQR, estimators, loop transfer recovery, margins and the design report."""
