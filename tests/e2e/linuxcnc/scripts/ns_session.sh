#!/usr/bin/env bash
# ns_session.sh INI KEEP...: one LinuxCNC session inside its own IPC, network, mount and PID
# namespaces (run.sh starts it under `unshare`), so that sessions run side by side on one machine.
# What two LinuxCNC 2.9 instances would otherwise share, and how each gets its own here:
#   - SysV shared memory with fixed keys (HAL, RTAPI, the NML buffers of linuxcnc.nml): the IPC
#     namespace;
#   - linuxcncsvr's TCP port 5005: the network namespace (only its loopback, brought up);
#   - /tmp/linuxcnc.lock (the script refuses, or offers to stop, a second instance) and its
#     /tmp/linuxcnc.{print,debug}.* and the rtapi socket: a private /tmp;
#   - the script's clean-up, which stops processes by name (pidof milltask, `realtime stop`): the
#     PID namespace, where it sees its own processes only.
# KEEP: the paths of the session under /tmp (its run directory, the harness, the programs), which
# stay visible at the same place on the private /tmp.
set -eu
INI=$1
shift
# the loopback up (SIOCGIFFLAGS / SIOCSIFFLAGS | IFF_UP): Python is there, iproute2 may not be
/usr/bin/python3 -c 'import fcntl, socket, struct
s = socket.socket()
flags = struct.unpack("16sH", fcntl.ioctl(s, 0x8913, struct.pack("16sH22x", b"lo", 0))[:18])[1]
fcntl.ioctl(s, 0x8914, struct.pack("16sH22x", b"lo", flags | 1))'
mount --make-rprivate /
cd /tmp     # the shared /tmp: still reachable as . once the private one covers the path
mount -t tmpfs -o mode=1777 rotacal-e2e-tmp /tmp
mount -t tmpfs -o mode=1777 rotacal-e2e-shm /dev/shm
for p in "$@"; do
  case $p in
    /tmp/*) ;;
    *) continue ;;
  esac
  top=${p#/tmp/}
  top=${top%%/*}
  [ -e "/tmp/$top" ] && continue
  if [ -d "./$top" ]; then mkdir "/tmp/$top"; else touch "/tmp/$top"; fi
  mount --no-canonicalize --bind "./$top" "/tmp/$top"   # ./: resolved from the shared /tmp
done
cd /
exec linuxcnc -r "$INI"
