"""Register-level chip models; `opentmcl.chips.tmc4210` is the TMC4210 motion controller."""
