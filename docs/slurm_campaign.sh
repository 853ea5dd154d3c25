#!/usr/bin/env bash
# A flume campaign on a Slurm cluster: one MPI job whose rank 0 hands out runs and is the only writer of the
# SQLite store; ranks 1..K-1 each run one `flume run` process at a time. If the job dies (a node lost, the
# allocation's time ending), submit the same script again: finished runs are kept, runs in flight are redone.
#
#   sbatch docs/slurm_campaign.sh scenes/campaigns/demo_waseda_2d.json study.sqlite
#
# The database must sit on a file system that honours POSIX locks for a single writer (a node-local or
# shared home directory; not an object store). Only rank 0 opens it.
#SBATCH --job-name=flume-campaign
#SBATCH --nodes=2
#SBATCH --ntasks-per-node=16
#SBATCH --cpus-per-task=1
#SBATCH --time=12:00:00
#SBATCH --output=flume-campaign-%j.log
set -euo pipefail
spec=${1:?usage: sbatch docs/slurm_campaign.sh SPEC.json DB.sqlite}
db=${2:?usage: sbatch docs/slurm_campaign.sh SPEC.json DB.sqlite}
flume=${FLUME:-build/bin/flume}
# Threads per run come from the spec's run.threads; keep cpus-per-task equal to it.
export OMP_NUM_THREADS=${SLURM_CPUS_PER_TASK:-1}
srun --mpi=pmix "$flume" campaign run "$spec" --db "$db" || mpirun "$flume" campaign run "$spec" --db "$db"
"$flume" campaign status --db "$db"
