/* dartspp command line: `dartspp render ...`, `dartspp compare ...`, `dartspp patch-mean ...`,
 * `dartspp merge ...`, `dartspp table ...`, `dartspp keys ...`, `dartspp counts ...`. Each returns the process exit
 * status: 0 success, 2 bad input (message on stderr), 1 other failures. */
#ifndef DARTSPP_CLI_H
#define DARTSPP_CLI_H

#include "dartspp/cluster.h"

int cli_render(int argc, char **argv);
/* The same with the render shared by the ranks of a cluster (NULL or one rank: cli_render); render_run
 * (include/dartspp/render.h) says who does what. */
int cli_render_cluster(int argc, char **argv, const render_cluster *cluster);
int cli_compare(int argc, char **argv);
int cli_patch_mean(int argc, char **argv);
int cli_merge(int argc, char **argv);
int cli_table(int argc, char **argv);
/* `dartspp keys [--markdown]`: every integrator and renderer key with type, default, range and meaning. */
int cli_keys(int argc, char **argv);
/* `dartspp counts CUBE.npy --output COUNTS.npy --pulses N --scale S ...`: photon-counting histograms of a
 * transient cube (include/dartspp/sensor.h). */
int cli_counts(int argc, char **argv);
/* Whether `-h` or `--help` is among a command's arguments: then the command prints its usage on stdout and
 * returns 0. */
int cli_help_asked(int argc, char **argv);

#endif
