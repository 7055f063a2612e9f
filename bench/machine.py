"""What the bench scripts say about the machine they ran on (the date and CPU model every result carries)."""
import platform


def cpu_model():
    """The CPU model from /proc/cpuinfo (the shell scripts' `grep -m1 'model name'`), else what Python knows."""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"
